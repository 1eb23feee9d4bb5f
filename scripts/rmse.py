#!/usr/bin/env python3
"""Root-mean-square error between two OpenEXR images, over all pixels and the R, G, B channels.

    python3 scripts/rmse.py IMAGE.exr REFERENCE.exr

Values are compared as stored (caustic writes linear 32-bit float RGB), with no clamping or
tone mapping. Needs the OpenEXR Python bindings (`pip install OpenEXR`, which brings numpy).
"""

import sys

try:
    import numpy as np
    import OpenEXR
except ImportError as e:
    sys.exit(f"rmse.py: {e}; install the bindings with `pip install OpenEXR`")


def read_rgb(path):
    """The image as a float64 array of shape (height, width, 3)."""
    if hasattr(OpenEXR, "File"):  # OpenEXR >= 3.3
        with OpenEXR.File(path) as f:
            channels = f.channels()
            if "RGB" in channels:
                rgb = channels["RGB"].pixels
            else:
                rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
        return np.asarray(rgb, dtype=np.float64)
    import Imath  # older bindings

    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    planes = [np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w) for c in "RGB"]
    return np.stack(planes, axis=-1).astype(np.float64)


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: python3 scripts/rmse.py IMAGE.exr REFERENCE.exr")
    a, b = (read_rgb(p) for p in sys.argv[1:])
    if a.shape != b.shape:
        sys.exit(f"rmse.py: image sizes differ: {a.shape[1]}x{a.shape[0]} and {b.shape[1]}x{b.shape[0]}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        sys.exit("rmse.py: an image contains non-finite values")
    print(f"{np.sqrt(np.mean((a - b) ** 2)):.6g}")


if __name__ == "__main__":
    main()
