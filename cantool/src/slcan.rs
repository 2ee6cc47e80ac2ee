//! A live bus through an SLCAN adapter (Lawicel's ASCII protocol, what python-can's
//! `slcan` interface, `slcand` and most USB-CAN adapters speak), named as python-can names
//! it: a serial device (`/dev/ttyACM0`, `COM3`) or `socket://HOST:PORT` (a TCP bridge,
//! such as QEMU's UART of the ECU image).
//!
//! On opening, `cw-can` closes the channel, sets the bit rate if asked (`Sn`) and opens it
//! (`O`), as python-can does. Then every line the adapter sends is a frame or skipped
//! (the adapter's replies `z`, `Z`, an empty line, version and serial number), or an error
//! that names its line (a refusal, BEL, is one): classic data frames (`t`, `T`, with the
//! adapter's optional time stamp, read by the ECU's own decoder
//! `cw_core::can::slcan::parse_adapter_line`), remote frames (`r`, `R`) and CAN FD frames
//! (`d`, `D`, and `b`, `B` with bit rate switch). Each frame's time stamp is the PC's
//! clock when its line arrived, as python-can's.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use cw_core::can::slcan;

use crate::asc::dlc_to_len;
use crate::frame::{Frame, FrameKind};
use crate::log::{At, Entry, LineError};

/// The longest line accepted (`D`, 8 id digits, the DLC, 128 data digits, a time stamp).
const LINE_MAX: usize = 1 + 8 + 1 + 128 + 4;

fn hex(bytes: &[u8]) -> Option<u32> {
    if bytes.is_empty() || bytes.len() > 8 {
        return None;
    }
    let text = std::str::from_utf8(bytes).ok()?;
    u32::from_str_radix(text, 16).ok()
}

/// One line from an adapter: a frame, `Ok(None)` for a line that is no frame, or what is
/// wrong with it.
pub fn parse_line(line: &[u8]) -> Result<Option<Frame>, String> {
    let Some((&first, rest)) = line.split_first() else {
        return Ok(None);
    };
    let shown = || String::from_utf8_lossy(line).into_owned();
    match first {
        b'z' | b'Z' | b'V' | b'N' if rest.len() <= 4 => Ok(None),
        0x07 => Err("the adapter refused a command (BEL)".into()),
        b't' | b'T' => {
            let (frame, _stamp) = cw_core::can::slcan::parse_adapter_line(line)
                .map_err(|e| format!("`{}`: {e:?}", shown()))?;
            Ok(Some(Frame::classic(
                frame.can_id().raw(),
                frame.can_id().is_extended(),
                frame.bytes(),
            )))
        }
        b'r' | b'R' | b'd' | b'D' | b'b' | b'B' => {
            let extended = first.is_ascii_uppercase();
            let digits = if extended { 8 } else { 3 };
            let id = rest
                .get(..digits)
                .and_then(hex)
                .filter(|id| *id <= if extended { 0x1FFF_FFFF } else { 0x7FF })
                .ok_or_else(|| format!("`{}`: no valid id", shown()))?;
            let dlc = rest
                .get(digits..=digits)
                .and_then(hex)
                .and_then(|d| u8::try_from(d).ok())
                .ok_or_else(|| format!("`{}`: no DLC", shown()))?;
            let body = rest.get(digits + 1..).unwrap_or(&[]);
            if matches!(first, b'r' | b'R') {
                if dlc > 8 {
                    return Err(format!("`{}`: DLC {dlc} on a remote frame", shown()));
                }
                // An optional time stamp may follow.
                if !(body.is_empty() || body.len() == 4) {
                    return Err(format!("`{}`: bad length", shown()));
                }
                return Ok(Some(Frame {
                    kind: FrameKind::Remote,
                    dlc: Some(dlc),
                    ..Frame::classic(id, extended, &[])
                }));
            }
            let len = dlc_to_len(dlc);
            if !(body.len() == 2 * len || body.len() == 2 * len + 4) {
                return Err(format!(
                    "`{}`: DLC {dlc:X} means {len} bytes, the line has {} digits",
                    shown(),
                    body.len()
                ));
            }
            let data = (0..len)
                .map(|i| body.get(2 * i..2 * i + 2).and_then(hex).map(|b| b as u8))
                .collect::<Option<Vec<u8>>>()
                .ok_or_else(|| format!("`{}`: data not hex", shown()))?;
            Ok(Some(Frame {
                kind: FrameKind::Fd {
                    brs: matches!(first, b'b' | b'B'),
                    esi: false,
                },
                ..Frame::classic(id, extended, &data)
            }))
        }
        _ => Err(format!("`{}` is no SLCAN frame", shown())),
    }
}

/// When to stop reading a live bus.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    /// After this many frames.
    pub frames: Option<usize>,
    /// After this long.
    pub duration: Option<Duration>,
}

/// Frames arriving from an adapter.
pub struct SlcanSource {
    port: Box<dyn ReadWrite>,
    channel: String,
    buf: Vec<u8>,
    pending: std::collections::VecDeque<u8>,
    line: usize,
    frames: usize,
    limits: Limits,
    started: Instant,
    done: bool,
}

/// Sends frames to an adapter: each a `t`/`T` line, as python-can's `slcan` writes them.
pub struct SlcanSender {
    out: Box<dyn Write + Send>,
    channel: String,
}

impl SlcanSender {
    /// A sender writing to any byte stream (a test's, say).
    pub fn over(out: Box<dyn Write + Send>, channel: &str) -> Self {
        Self {
            out,
            channel: channel.to_string(),
        }
    }

    /// Writes `frame`'s line.
    ///
    /// # Errors
    /// A frame SLCAN's `t`/`T` lines cannot carry (CAN FD, remote, error, over 8 bytes),
    /// or the adapter's connection fails.
    pub fn send(&mut self, frame: &Frame) -> Result<(), String> {
        let classic = frame.to_classic().ok_or_else(|| {
            format!("{frame}: only classic data frames of at most 8 bytes are sent over SLCAN")
        })?;
        let mut line = [0u8; slcan::FRAME_LINE_MAX];
        let n = slcan::encode_frame(&classic, &mut line);
        self.out
            .write_all(line.get(..n).unwrap_or(&[]))
            .and_then(|()| self.out.flush())
            .map_err(|e| format!("{}: cannot write to the adapter: {e}", self.channel))
    }
}

/// A connection to an adapter, and a second handle on it for writing.
type Connection = (Box<dyn ReadWrite>, Box<dyn Write + Send>);

/// Opens `url` (`socket://HOST:PORT`, or a serial device at `baud`) with a 100 ms read
/// timeout (a serial device's also bounds its writes; a socket's writes give up after 1 s,
/// so an adapter that stops reading cannot hold the view).
fn connect(url: &str, baud: u32) -> Result<Connection, String> {
    match url.strip_prefix("socket://") {
        Some(addr) => {
            let stream =
                TcpStream::connect(addr).map_err(|e| format!("cannot connect to {addr}: {e}"))?;
            stream
                .set_read_timeout(Some(Duration::from_millis(100)))
                .and_then(|()| stream.set_write_timeout(Some(Duration::from_secs(1))))
                .map_err(|e| format!("{addr}: {e}"))?;
            let out = stream.try_clone().map_err(|e| format!("{addr}: {e}"))?;
            Ok((Box::new(stream), Box::new(out)))
        }
        None => {
            let port = serialport::new(url, baud)
                .timeout(Duration::from_millis(100))
                .open()
                .map_err(|e| format!("cannot open {url}: {e}"))?;
            let out = port.try_clone().map_err(|e| format!("{url}: {e}"))?;
            Ok((Box::new(port), Box::new(out)))
        }
    }
}

/// A byte stream both ways.
pub trait ReadWrite: Read + Write + Send {}
impl<T: Read + Write + Send> ReadWrite for T {}

impl SlcanSource {
    /// Opens `url` (`socket://HOST:PORT` or a serial device at `baud`), then closes,
    /// sets the bit rate (`bitrate`, the `Sn` index 0..=8) if given, and opens the
    /// channel.
    ///
    /// # Errors
    /// The connection or the device cannot be opened, or the commands not written.
    pub fn open(url: &str, baud: u32, bitrate: Option<u8>, limits: Limits) -> Result<Self, String> {
        let (port, _) = connect(url, baud)?;
        Self::over(port, url, bitrate, limits)
    }

    /// [`Self::open`], with a second handle on the same connection for sending frames
    /// (the view's sender panel).
    ///
    /// # Errors
    /// As [`Self::open`].
    pub fn open_with_sender(
        url: &str,
        baud: u32,
        bitrate: Option<u8>,
        limits: Limits,
    ) -> Result<(Self, SlcanSender), String> {
        let (port, out) = connect(url, baud)?;
        let source = Self::over(port, url, bitrate, limits)?;
        Ok((
            source,
            SlcanSender {
                out,
                channel: url.to_string(),
            },
        ))
    }

    /// The same over any byte stream (a test's, say).
    ///
    /// # Errors
    /// The commands cannot be written.
    pub fn over(
        mut port: Box<dyn ReadWrite>,
        channel: &str,
        bitrate: Option<u8>,
        limits: Limits,
    ) -> Result<Self, String> {
        let mut init = b"C\r".to_vec();
        if let Some(n) = bitrate {
            if n > 8 {
                return Err(format!(
                    "bit rate index {n}: SLCAN's are 0 (10 kbit/s) to 8 (1 Mbit/s)"
                ));
            }
            init.extend_from_slice(format!("S{n}\r").as_bytes());
        }
        init.extend_from_slice(b"O\r");
        port.write_all(&init)
            .and_then(|()| port.flush())
            .map_err(|e| format!("{channel}: cannot write to the adapter: {e}"))?;
        Ok(Self {
            port,
            channel: channel.to_string(),
            buf: Vec::new(),
            pending: std::collections::VecDeque::new(),
            line: 0,
            frames: 0,
            limits,
            started: Instant::now(),
            done: false,
        })
    }

    fn out_of_time(&self) -> bool {
        self.limits
            .duration
            .is_some_and(|d| self.started.elapsed() >= d)
    }

    /// The next whole line, or `None` when the stream ends or a limit is reached.
    fn next_line(&mut self) -> Option<Result<Vec<u8>, LineError>> {
        let mut chunk = [0u8; 512];
        loop {
            while let Some(b) = self.pending.pop_front() {
                if b == b'\r' || b == b'\n' {
                    self.line += 1;
                    let line = std::mem::take(&mut self.buf);
                    if line.len() > LINE_MAX {
                        return Some(Err(LineError::line(self.line, "line too long")));
                    }
                    return Some(Ok(line));
                }
                if b == 0x07 {
                    // BEL ends a refusal without a carriage return.
                    self.line += 1;
                    self.buf.clear();
                    return Some(Ok(vec![0x07]));
                }
                if self.buf.len() <= LINE_MAX {
                    self.buf.push(b);
                }
            }
            if self.out_of_time() {
                return None;
            }
            match self.port.read(&mut chunk) {
                Ok(0) => return None,
                Ok(n) => self.pending.extend(chunk.get(..n).unwrap_or(&[])),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => {
                    self.done = true;
                    return Some(Err(LineError::line(
                        self.line + 1,
                        format!("cannot read: {e}"),
                    )));
                }
            }
        }
    }
}

impl Iterator for SlcanSource {
    type Item = Result<(At, Entry), LineError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.done || self.limits.frames.is_some_and(|n| self.frames >= n) {
                return None;
            }
            let line = match self.next_line()? {
                Ok(line) => line,
                Err(e) => return Some(Err(e)),
            };
            match parse_line(&line) {
                Ok(None) => continue,
                Ok(Some(frame)) => {
                    self.frames += 1;
                    let timestamp = SystemTime::now()
                        .duration_since(UNIX_EPOCH)
                        .map_or(0.0, |d| d.as_secs_f64());
                    return Some(Ok((
                        At::Line(self.line),
                        Entry {
                            timestamp,
                            channel: self.channel.clone(),
                            frame,
                        },
                    )));
                }
                Err(what) => return Some(Err(LineError::line(self.line, what))),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_frame_line_an_adapter_sends_is_read() {
        let frame = |l: &str| parse_line(l.as_bytes()).map(|f| f.map(|f| f.to_string()));
        assert_eq!(frame("t1002AABB"), Ok(Some("100#AABB".into())));
        assert_eq!(frame("t1002AABB1234"), Ok(Some("100#AABB".into())));
        assert_eq!(frame("T123456780"), Ok(Some("12345678#".into())));
        assert_eq!(frame("r1004"), Ok(Some("100#R4".into())));
        assert_eq!(frame("R123456788"), Ok(Some("12345678#R8".into())));
        assert_eq!(
            frame("d1009000102030405060708090A0B"),
            Ok(Some("100##0000102030405060708090A0B".into()))
        );
        assert_eq!(frame("B123456781AA"), Ok(Some("12345678##1AA".into())));
        assert_eq!(frame("z"), Ok(None));
        assert_eq!(frame("V0101"), Ok(None));
        assert!(frame("\x07").is_err());
        assert!(frame("t8001AA").is_err());
        assert!(frame("d1009AA").is_err());
        assert!(frame("r1009").is_err());
        assert!(frame("x").is_err());
    }

    #[test]
    fn the_sender_writes_the_line_the_adapter_reads_back_on_the_same_connection() {
        let Ok(listener) = std::net::TcpListener::bind("127.0.0.1:0") else {
            panic!("a free port")
        };
        let Ok(addr) = listener.local_addr() else {
            panic!("its address")
        };
        let adapter = std::thread::spawn(move || {
            let Ok((mut s, _)) = listener.accept() else {
                panic!("a connection")
            };
            let mut got = Vec::new();
            let mut buf = [0u8; 64];
            while !got.ends_with(b"t2004F401E803\r") {
                match s.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => got.extend_from_slice(buf.get(..n).unwrap_or(&[])),
                }
            }
            got
        });
        let url = format!("socket://{addr}");
        let Ok((_source, mut sender)) =
            SlcanSource::open_with_sender(&url, 0, Some(6), Limits::default())
        else {
            panic!("the fake adapter opens")
        };
        let config = Frame::classic(0x200, false, &[0xF4, 0x01, 0xE8, 0x03]);
        assert_eq!(sender.send(&config), Ok(()));
        let fd = Frame {
            kind: FrameKind::Fd {
                brs: false,
                esi: false,
            },
            ..config.clone()
        };
        assert!(sender.send(&fd).is_err(), "SLCAN's t lines are classic");
        assert!(
            sender.send(&Frame::classic(0x800, false, &[])).is_err(),
            "an 11-bit id"
        );
        match adapter.join() {
            Ok(got) => assert_eq!(got, b"C\rS6\rO\rt2004F401E803\r"),
            Err(_) => panic!("the fake adapter failed"),
        }
    }

    #[test]
    fn any_line_is_a_frame_that_reads_back_or_an_error() {
        bolero::check!().with_type::<Vec<u8>>().for_each(|line| {
            if let Ok(Some(frame)) = parse_line(line) {
                assert!(frame.data.len() <= 64);
                assert!(crate::frame::parse(&frame.to_string()).is_ok());
            }
        });
    }
}
