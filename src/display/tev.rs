//! The messages of the tev image viewer's TCP protocol that a renderer sends (the protocol pbrt-v4
//! uses for `--display-server`): create an image with named channels, then update rectangles of
//! it. Every message is a little-endian `u32` length (counting itself), a one-byte type and its
//! fields: strings end with a NUL byte, integers are little-endian `i32`, pixel values `f32`.
//!
//! Updates use tev's second update message (type 5), which carries several channels at once, each
//! as a plane of `width x height` values in row order, one plane after the other; tev has read it
//! since 2019. The first (type 3) would need a message per channel.

/// Message types (tev's `IpcPacket::EType`).
pub const CREATE_IMAGE: u8 = 4;
pub const UPDATE_IMAGE_CHANNELS: u8 = 5;

/// Builds one message: reserves the length, lets `body` write the rest, fills the length in.
fn message(kind: u8, body: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut m = vec![0u8; 4];
    m.push(kind);
    body(&mut m);
    let len = u32::try_from(m.len()).expect("display messages are split well below 4 GiB");
    m[..4].copy_from_slice(&len.to_le_bytes());
    m
}

fn string(m: &mut Vec<u8>, s: &str) {
    // A NUL inside a name would end it early on the viewer's side: drop it.
    m.extend(s.bytes().filter(|&b| b != 0));
    m.push(0);
}

fn int(m: &mut Vec<u8>, v: u32) {
    // Image sizes are at most `scene::desc::MAX_SIDE`, far below `i32::MAX`.
    m.extend_from_slice(&(v.min(i32::MAX as u32) as i32).to_le_bytes());
}

/// Creates (or replaces) the image `name`, `width x height`, with `channels` (all zero), and
/// brings it to the front.
pub fn create_image(name: &str, width: u32, height: u32, channels: &[String]) -> Vec<u8> {
    message(CREATE_IMAGE, |m| {
        m.push(1); // grab focus
        string(m, name);
        int(m, width);
        int(m, height);
        int(m, channels.len() as u32);
        for c in channels {
            string(m, c);
        }
    })
}

/// Sets the rectangle at (`x`, `y`) of `width x height` pixels in every channel of image `name`;
/// `planes` holds one plane per channel, in the order of `channels`.
pub fn update_image(name: &str, channels: &[String], rect: [u32; 4], planes: &[f32]) -> Vec<u8> {
    let [x, y, width, height] = rect;
    debug_assert_eq!(planes.len(), channels.len() * width as usize * height as usize);
    message(UPDATE_IMAGE_CHANNELS, |m| {
        m.reserve(planes.len() * 4 + 64);
        m.push(0); // leave the focus where the user put it
        string(m, name);
        int(m, channels.len() as u32);
        for c in channels {
            string(m, c);
        }
        for v in [x, y, width, height] {
            int(m, v);
        }
        for v in planes {
            m.extend_from_slice(&v.to_le_bytes());
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_carry_their_length_type_and_fields() {
        let names = vec!["R".to_string(), "direct.G".to_string()];
        let c = create_image("box\0.exr", 3, 2, &names);
        assert_eq!(u32::from_le_bytes(c[..4].try_into().unwrap()) as usize, c.len());
        assert_eq!(c[4], CREATE_IMAGE);
        assert_eq!(c[5], 1);
        assert_eq!(&c[6..14], b"box.exr\0");
        assert_eq!(&c[14..26], &[3, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0]);
        assert_eq!(&c[26..], b"R\0direct.G\0");

        let planes = [1.0f32, 2.0, 3.0, 4.0];
        let u = update_image("i", &names, [1, 0, 2, 1], &planes);
        assert_eq!(u32::from_le_bytes(u[..4].try_into().unwrap()) as usize, u.len());
        assert_eq!(u[4], UPDATE_IMAGE_CHANNELS);
        assert_eq!(&u[5..8], &[0, b'i', 0]);
        assert_eq!(&u[8..12], &2i32.to_le_bytes());
        assert_eq!(&u[12..23], b"R\0direct.G\0");
        assert_eq!(&u[23..39], &[1, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0]);
        let values: Vec<f32> = u[39..].chunks(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        assert_eq!(values, planes);
    }
}
