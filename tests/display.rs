//! `--display-server`: a small stand-in for the tev image viewer (a TCP listener that reads tev's
//! messages and keeps the images they build, written here from the protocol independently of
//! the sender in `caustic::display::tev`) receives the render and its updates, and ends up
//! holding the image that was written; a viewer that cannot be reached, or that goes away
//! during the render, costs a warning and nothing else.

mod common;

use caustic::film::Image;
use caustic::film::output::read_exr;
use std::collections::HashMap;
use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::thread::JoinHandle;

fn caustic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_caustic"))
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// An image the viewer holds: width, height and each channel's plane of row-major values.
type Held = (u32, u32, HashMap<String, Vec<f32>>);

/// What the stand-in viewer was told.
#[derive(Default, Debug)]
struct Viewer {
    /// (name, width, height, channels) of each image created.
    created: Vec<(String, u32, u32, Vec<String>)>,
    /// Each image by name.
    images: HashMap<String, Held>,
    /// Update messages received, and how many of them started at the image's top-left corner
    /// (one per picture sent: a picture is one message here unless it is very large).
    updates: usize,
    pictures: usize,
}

/// Reads the fields of one message in order.
struct Fields<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.at + n <= self.bytes.len(), "message ends early");
        self.at += n;
        &self.bytes[self.at - n..self.at]
    }
    fn byte(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn int(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn long(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn float(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.bytes[self.at..].iter().position(|&b| b == 0).expect("string without its NUL");
        let s = String::from_utf8(self.bytes[self.at..self.at + end].to_vec()).unwrap();
        self.at += end + 1;
        s
    }
}

impl Viewer {
    /// Applies one message (its length field included).
    fn apply(&mut self, message: &[u8]) {
        let mut f = Fields { bytes: message, at: 4 };
        let kind = f.byte();
        match kind {
            // CreateImage: focus, name, width, height, channel count, channel names.
            4 => {
                let _focus = f.byte();
                let name = f.string();
                let (w, h, n) = (f.int() as u32, f.int() as u32, f.int() as usize);
                let channels: Vec<String> = (0..n).map(|_| f.string()).collect();
                let planes = channels.iter().map(|c| (c.clone(), vec![0.0; (w * h) as usize])).collect();
                self.created.push((name.clone(), w, h, channels));
                self.images.insert(name, (w, h, planes));
            }
            // UpdateImage: one channel (3), several as planes (5), several with offsets and
            // strides (6).
            3 | 5 | 6 => {
                let _focus = f.byte();
                let name = f.string();
                let n = if kind == 3 { 1 } else { f.int() as usize };
                let channels: Vec<String> = (0..n).map(|_| f.string()).collect();
                let (x, y, w, h) = (f.int() as usize, f.int() as usize, f.int() as usize, f.int() as usize);
                let (offsets, strides): (Vec<i64>, Vec<i64>) = if kind == 6 {
                    let o = (0..n).map(|_| f.long()).collect();
                    (o, (0..n).map(|_| f.long()).collect())
                } else {
                    ((0..n).map(|c| (c * w * h) as i64).collect(), vec![1; n])
                };
                let values: Vec<f32> = std::iter::from_fn(|| (f.at < f.bytes.len()).then(|| f.float())).collect();
                let (iw, _, planes) = self.images.get_mut(&name).expect("update of an image never created");
                for (c, channel) in channels.iter().enumerate() {
                    let plane = planes.get_mut(channel).expect("update of a channel never created");
                    for j in 0..h {
                        for i in 0..w {
                            let v = values[(offsets[c] + (j * w + i) as i64 * strides[c]) as usize];
                            plane[(y + j) * *iw as usize + x + i] = v;
                        }
                    }
                }
                self.updates += 1;
                if x == 0 && y == 0 {
                    self.pictures += 1;
                }
            }
            other => panic!("unexpected message type {other}"),
        }
    }

    /// The image `name`'s channels `prefix` R, G, B as an image.
    fn image(&self, name: &str, prefix: &str) -> Image {
        let (w, h, planes) = &self.images[name];
        let mut img = Image::new(*w, *h);
        let plane = |c: &str| &planes[&format!("{prefix}{c}")];
        let (r, g, b) = (plane("R"), plane("G"), plane("B"));
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = caustic::math::Color::new(r[k], g[k], b[k]);
        }
        img
    }
}

/// Reads messages from `stream` until it closes (or, with `stop_after`, until that many have
/// arrived, then closes it).
fn serve(mut stream: TcpStream, viewer: &mut Viewer, stop_after: Option<usize>) {
    let mut buf = Vec::new();
    let mut chunk = [0u8; 1 << 16];
    let mut seen = 0;
    loop {
        while buf.len() >= 4 {
            let len = u32::from_le_bytes(buf[..4].try_into().unwrap()) as usize;
            assert!(len >= 5, "message of {len} bytes");
            if buf.len() < len {
                break;
            }
            viewer.apply(&buf[..len]);
            buf.drain(..len);
            seen += 1;
            if stop_after == Some(seen) {
                return;
            }
        }
        match stream.read(&mut chunk) {
            Ok(0) => {
                assert!(buf.is_empty(), "the connection closed in the middle of a message");
                return;
            }
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) => panic!("reading from the renderer: {e}"),
        }
    }
}

/// A viewer on a free port of this machine, serving one connection on a thread.
fn start_viewer(stop_after: Option<usize>) -> (String, JoinHandle<Viewer>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let thread = std::thread::spawn(move || {
        let mut viewer = Viewer::default();
        let (stream, _) = listener.accept().unwrap();
        serve(stream, &mut viewer, stop_after);
        // Dropping the listener too: the renderer cannot connect again.
        viewer
    });
    (address, thread)
}

fn render(address: &str, out: &Path, extra: &[&str]) -> Output {
    caustic()
        .arg("render")
        .arg(scene("13-cornell-caustics.toml"))
        .args(["--width", "48", "--height", "36", "--integrator", "path", "--display-server", address, "-o"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn the_viewer_receives_the_render_its_updates_and_its_layers_and_ends_with_the_written_image() {
    let dir = common::scratch("display");
    let out = dir.join("box.exr");
    let (address, viewer) = start_viewer(None);
    // A time budget of 4.5 s: the first pass, updates 2 s apart and the last picture.
    let run = render(&address, &out, &["--time", "4.5", "--layers", "-q"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let viewer = viewer.join().unwrap();
    let channels: Vec<String> = std::iter::once(String::new())
        .chain(caustic::film::LAYER_NAMES.map(|l| format!("{l}.")))
        .flat_map(|p| ["R", "G", "B"].map(|c| format!("{p}{c}")))
        .collect();
    assert_eq!(viewer.created, vec![("box.exr".to_string(), 48, 36, channels)]);
    assert!(viewer.pictures >= 3, "{} pictures (first pass, at least one update, the last)", viewer.pictures);
    assert_eq!(viewer.updates, viewer.pictures, "small pictures go in one message each");
    let written = read_exr(&out).unwrap();
    assert!(written.mean().max_element() > 0.0);
    assert_eq!(viewer.image("box.exr", ""), written, "the viewer's last picture is the written image");
    for layer in caustic::film::LAYER_NAMES {
        let file = read_exr(&dir.join(format!("box.{layer}.exr"))).unwrap();
        assert_eq!(viewer.image("box.exr", &format!("{layer}.")), file, "layer {layer}");
    }
}

#[test]
fn an_unreachable_viewer_is_a_warning_and_the_image_is_written() {
    let dir = common::scratch("display-unreachable");
    let out = dir.join("u.exr");
    // A port that was free a moment ago: nothing listens there.
    let address = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().to_string();
    let run = render(&address, &out, &["--spp", "4", "-q"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("warning: display server {address}: cannot connect")), "{stderr}");
    assert_eq!(stderr.matches("warning").count(), 1, "{stderr}");
    assert!(read_exr(&out).unwrap().mean().max_element() > 0.0);
}

#[test]
fn a_viewer_that_goes_away_mid_render_is_a_warning_and_the_image_is_written() {
    let dir = common::scratch("display-lost");
    let out = dir.join("l.exr");
    // The viewer takes the image's creation and the first picture, then closes the connection
    // and stops listening.
    let (address, viewer) = start_viewer(Some(2));
    let run = render(&address, &out, &["--time", "5", "-q"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("warning: display server {address}: the connection was lost")), "{stderr}");
    let viewer = viewer.join().unwrap();
    assert_eq!(viewer.pictures, 1);
    assert!(read_exr(&out).unwrap().mean().max_element() > 0.0);
}

#[test]
fn a_bad_address_is_refused_before_rendering() {
    let out = common::scratch("display-bad").join("b.exr");
    let run = render("localhost", &out, &["--spp", "1"]);
    assert_eq!(run.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("expected HOST:PORT"), "{stderr}");
    assert!(!out.exists());
}
