//! Live display of a render in the tev image viewer (`--display-server HOST:PORT`, as pbrt-v4
//! has it): the render driver hands a [`Viewer`] the picture so far after its first pass, every
//! [`INTERVAL`] after that and at the end, and the viewer sends it over TCP (`tev`: the
//! messages) from a thread of its own, so a slow or dead connection never holds up the render.
//!
//! The display is a convenience, never a reason to fail: an unreachable viewer, or one that goes
//! away during the render, is one warning on stderr, and the viewer tries to connect again at most
//! every [`RETRY`] (a tev started late, or restarted, picks the render up with its next picture).

pub mod tev;

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How often the driver sends the picture (besides after the first pass and at the end).
pub const INTERVAL: Duration = Duration::from_secs(2);
/// How long after a failed connection the next attempt may be made.
pub const RETRY: Duration = Duration::from_secs(5);
/// Longest wait for a connection to be accepted.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);
/// Longest wait for one message to be taken by the viewer before the connection counts as lost.
const WRITE_TIMEOUT: Duration = Duration::from_secs(10);
/// Largest update message: big images go as bands of rows, so tev's buffer stays small.
const MAX_MESSAGE_BYTES: usize = 8 << 20;

/// Where to show a render: the viewer's `HOST:PORT` and the image's name there (a later render
/// under the same name replaces it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DisplayTarget {
    pub address: String,
    pub name: String,
}

/// A picture to show: one plane of `width x height` values (rows top to bottom) per channel, in
/// the order of `channels` (`R`, `G`, `B`, then `direct.R` etc. for layers).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub channels: Vec<String>,
    pub planes: Vec<f32>,
}

/// Sends pictures to a tev viewer from a background thread; the newest picture not yet sent
/// replaces an older one, so a slow connection skips pictures rather than queueing them.
pub struct Viewer {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

struct Shared {
    state: Mutex<Pending>,
    wake: Condvar,
}

#[derive(Default)]
struct Pending {
    frame: Option<Frame>,
    finished: bool,
}

impl Viewer {
    /// Starts the thread that connects to `target.address` and sends what `show` gives it.
    pub fn start(target: &DisplayTarget) -> Viewer {
        let shared = Arc::new(Shared { state: Mutex::new(Pending::default()), wake: Condvar::new() });
        let link = Link::new(target.clone());
        let inner = shared.clone();
        let thread = std::thread::Builder::new().name("display".into()).spawn(move || send_loop(link, &inner));
        match thread {
            Ok(t) => Viewer { shared, thread: Some(t) },
            Err(e) => {
                eprintln!(
                    "warning: display server {}: cannot start its thread ({e}); rendering without it",
                    target.address
                );
                Viewer { shared, thread: None }
            }
        }
    }

    /// Queues `frame` to be sent (in place of one still waiting).
    pub fn show(&self, frame: Frame) {
        if self.thread.is_none() {
            return;
        }
        let mut p = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
        p.frame = Some(frame);
        self.shared.wake.notify_one();
    }

    /// Sends the last picture queued and waits until it has been sent or given up on (each
    /// message is bounded by the write timeout).
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        {
            let mut p = self.shared.state.lock().unwrap_or_else(|e| e.into_inner());
            p.finished = true;
            self.shared.wake.notify_one();
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.stop();
    }
}

fn send_loop(mut link: Link, shared: &Shared) {
    loop {
        let frame = {
            let mut p = shared.state.lock().unwrap_or_else(|e| e.into_inner());
            while p.frame.is_none() && !p.finished {
                p = shared.wake.wait(p).unwrap_or_else(|e| e.into_inner());
            }
            match p.frame.take() {
                Some(f) => f,
                None => return,
            }
        };
        link.send(&frame);
    }
}

/// The connection to the viewer and what it has been told.
struct Link {
    target: DisplayTarget,
    stream: Option<TcpStream>,
    /// The size and channels of the image created on this connection, if any.
    created: Option<(u32, u32, Vec<String>)>,
    last_attempt: Option<Instant>,
    /// The last connection or send failed (and was said); the next success says so too.
    failing: bool,
}

impl Link {
    fn new(target: DisplayTarget) -> Self {
        Link { target, stream: None, created: None, last_attempt: None, failing: false }
    }

    fn warn(&mut self, what: &str) {
        if !self.failing {
            eprintln!(
                "warning: display server {}: {what}; the render goes on (it will try again every {} s)",
                self.target.address,
                RETRY.as_secs()
            );
        }
        self.failing = true;
    }

    fn send(&mut self, frame: &Frame) {
        if self.stream.is_none() {
            if self.last_attempt.is_some_and(|t| t.elapsed() < RETRY) {
                return;
            }
            self.last_attempt = Some(Instant::now());
            match connect(&self.target.address) {
                Ok(s) => {
                    self.stream = Some(s);
                    self.created = None;
                }
                Err(e) => return self.warn(&format!("cannot connect ({e})")),
            }
        }
        match self.write(frame) {
            Ok(()) => {
                if self.failing {
                    eprintln!("display server {}: connected, showing the render again", self.target.address);
                }
                self.failing = false;
            }
            Err(e) => {
                self.stream = None;
                self.created = None;
                self.last_attempt = Some(Instant::now());
                self.warn(&format!("the connection was lost ({e})"));
            }
        }
    }

    fn write(&mut self, frame: &Frame) -> std::io::Result<()> {
        let Some(stream) = self.stream.as_mut() else { return Ok(()) };
        let name = &self.target.name;
        let shape = (frame.width, frame.height, frame.channels.clone());
        if self.created.as_ref() != Some(&shape) {
            stream.write_all(&tev::create_image(name, frame.width, frame.height, &frame.channels))?;
            self.created = Some(shape);
        }
        let (w, h) = (frame.width as usize, frame.height as usize);
        let row_bytes = (w * frame.channels.len() * 4).max(1);
        let rows = (MAX_MESSAGE_BYTES / row_bytes).clamp(1, h.max(1));
        let mut band = Vec::with_capacity(rows * w * frame.channels.len());
        for y0 in (0..h).step_by(rows) {
            let y1 = (y0 + rows).min(h);
            band.clear();
            for plane in frame.planes.chunks_exact(w * h) {
                band.extend_from_slice(&plane[y0 * w..y1 * w]);
            }
            let rect = [0, y0 as u32, frame.width, (y1 - y0) as u32];
            stream.write_all(&tev::update_image(name, &frame.channels, rect, &band))?;
        }
        stream.flush()
    }
}

fn connect(address: &str) -> std::io::Result<TcpStream> {
    let mut last = None;
    for addr in address.to_socket_addrs()? {
        match TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
            Ok(s) => {
                s.set_write_timeout(Some(WRITE_TIMEOUT))?;
                let _ = s.set_nodelay(true);
                return Ok(s);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no address found")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn frame(v: f32) -> Frame {
        Frame { width: 2, height: 1, channels: vec!["R".into(), "G".into(), "B".into()], planes: vec![v; 6] }
    }

    #[test]
    fn an_unreachable_viewer_neither_blocks_nor_fails() {
        // A port that was just free: the connection is refused at once.
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let v = Viewer::start(&DisplayTarget { address: format!("127.0.0.1:{port}"), name: "x".into() });
        v.show(frame(1.0));
        let t = Instant::now();
        v.finish();
        assert!(t.elapsed() < CONNECT_TIMEOUT, "{:?}", t.elapsed());
    }

    #[test]
    fn the_viewer_creates_the_image_once_and_sends_the_last_frame() {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap().to_string();
        let server = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            let mut all = Vec::new();
            s.read_to_end(&mut all).unwrap();
            all
        });
        let v = Viewer::start(&DisplayTarget { address, name: "img".into() });
        v.show(frame(0.5));
        v.finish();
        let bytes = server.join().unwrap();
        let create = tev::create_image("img", 2, 1, &frame(0.0).channels);
        assert!(bytes.starts_with(&create));
        let update = tev::update_image("img", &frame(0.0).channels, [0, 0, 2, 1], &[0.5; 6]);
        assert_eq!(&bytes[create.len()..], &update[..]);
    }
}
