//! A MAVLink 2 link over UDP, TCP or a serial port: the `mavlink` crate frames, checks and
//! parses every message (common dialect); this module owns the socket or the device, so that a
//! test can bind port 0 and learn the port, a loop can wait with a timeout, and every frame can
//! be logged.
//!
//! Addresses (the `mavlink` crate's spelling; `KIND://REST` is accepted too):
//!
//! * `udpin:HOST:PORT` listens on `HOST:PORT` and writes to every address that sent it a valid
//!   frame: a ground station and a companion at once, at most [`MAX_PEERS`];
//! * `udpout:HOST:PORT` writes to `HOST:PORT` from a free local port;
//! * `tcpin:HOST:PORT` listens for TCP connections and writes to every connected client, at
//!   most [`MAX_PEERS`];
//! * `tcpout:HOST:PORT` connects to `HOST:PORT` (refused at once if nobody listens there; a
//!   connection that drops is tried again every second);
//! * `serial:DEVICE:BAUD` opens a serial port (a terminal device: `/dev/ttyUSB0:57600`), raw
//!   8N1 without flow control, at one of [`BAUD_RATES`].
//!
//! Peers (`udpin:`, `tcpin:`): a peer silent (no valid frame) for the peer timeout
//! ([`Link::set_peer_timeout`], default [`DEFAULT_PEER_TIMEOUT`]) is dropped (a TCP client is
//! disconnected); a new peer takes a free place or a silent one's, and is refused while
//! [`MAX_PEERS`] others are alive (counted in [`LinkStats::peers_refused`]), so a flood of
//! spoofed source addresses neither grows the set nor pushes out the peers that are talking.
//! A TCP client that has not yet sent a valid frame holds its place on trial: it is
//! disconnected after [`HANDSHAKE_TIMEOUT`] (or the peer timeout, if shorter) without one, and
//! a new client, when every place is taken, takes the place of the oldest such client; so idle
//! connections (a port scanner, a client of another protocol, a hostile peer holding sockets
//! open) never lock a real client out.
//!
//! Hostile traffic: bytes that are not a MAVLink 2 frame with a valid checksum are skipped
//! (counted in [`LinkStats::junk_datagrams`] when a UDP datagram yields nothing), message ids
//! outside the common dialect are dropped, and one call reads at most
//! [`MAX_DATAGRAMS_PER_POLL`] datagrams (at most [`MAX_FRAMES_PER_POLL`] frames of a stream),
//! so a flood delays a loop but never starves it. A stream's outgoing bytes wait in a queue of
//! at most [`MAX_QUEUED_BYTES`] (whole frames only: a reader that stops reading loses frames,
//! never half of one).

use mavlink::dialects::common::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{MAVLinkMessageRaw, MavHeader, MavlinkReader, MavlinkVersion, Message as _};
use std::fs::File;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs, UdpSocket};
use std::os::fd::{AsRawFd, FromRawFd, RawFd};
use std::path::Path;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The most peers a `udpin:` or `tcpin:` link writes to.
pub const MAX_PEERS: usize = 8;

/// The most datagrams one [`Link::poll`] reads.
pub const MAX_DATAGRAMS_PER_POLL: usize = 256;

/// The most frames one [`Link::poll`] reads from one stream (a TCP connection, a serial port).
pub const MAX_FRAMES_PER_POLL: usize = 1024;

/// The most bytes waiting to be written to one stream; a frame that would not fit is dropped
/// ([`LinkStats::frames_dropped`]).
pub const MAX_QUEUED_BYTES: usize = 256 * 1024;

/// How long a peer may be silent before it is dropped, unless [`Link::set_peer_timeout`] says
/// otherwise.
pub const DEFAULT_PEER_TIMEOUT: Duration = Duration::from_secs(10);

/// How long a TCP client of a `tcpin:` link may stay connected without sending a valid frame
/// (a MAVLink client sends its first heartbeat within a second of connecting).
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(3);

/// The baud rates `serial:DEVICE:BAUD` accepts (the POSIX and Linux termios speeds).
pub const BAUD_RATES: [u32; 26] = [
    110, 150, 300, 600, 1200, 1800, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800,
    500000, 576000, 921600, 1000000, 1152000, 1500000, 2000000, 2500000, 3000000, 3500000, 4000000,
];

/// A link that cannot be opened.
#[derive(Debug)]
pub enum LinkError {
    /// The address is not one this bridge speaks (a usage error).
    Address(String),
    /// The socket cannot be had (an operating-system error).
    Io(String),
    /// A serial device that is missing, unreadable or not a terminal device (a FIFO, a regular
    /// file, a directory).
    Device(String),
    /// Nobody answers at the address (`tcpout:` to a port where nobody listens).
    Unavailable(String),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Address(m)
            | LinkError::Io(m)
            | LinkError::Device(m)
            | LinkError::Unavailable(m) => f.write_str(m),
        }
    }
}

/// A received message and its sender.
#[derive(Clone, Debug)]
pub struct Received {
    /// The sender's system, component and sequence number.
    pub header: MavHeader,
    /// The message.
    pub msg: MavMessage,
    /// The datagram's source address (UDP; `None` on a stream): two senders with the same
    /// system and component id are told apart by it.
    pub from: Option<SocketAddr>,
    /// A `COMMAND_ACK`'s MAVLink 2 extension fields `target_system` and `target_component`
    /// (payload bytes 8 and 9; 0 where the frame leaves them out, unaddressed), which the
    /// `mavlink` crate's common dialect does not decode: whom the acknowledgement answers.
    pub ack_target: Option<(u8, u8)>,
}

/// What the link has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Datagrams read (UDP).
    pub datagrams: u64,
    /// Datagrams without one valid frame of the common dialect (UDP), and not
    /// [`LinkStats::other_dialect_datagrams`]: damaged or foreign bytes.
    pub junk_datagrams: u64,
    /// Datagrams holding only well-formed MAVLink 2 frames of messages outside the common
    /// dialect (ArduPilot's `MEMINFO`, `AHRS2`, `HWSTATUS`: a large share of an ArduPilot link),
    /// skipped as a stream's are, not counted as junk (UDP; their checksums cannot be checked
    /// without their dialect).
    pub other_dialect_datagrams: u64,
    /// Valid frames read.
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// MAVLink 1 frames (valid checksum) received and dropped: this bridge speaks MAVLink 2.
    pub mavlink1_frames: u64,
    /// Peers dropped after the peer timeout of silence (or a TCP connection that closed).
    pub peers_evicted: u64,
    /// New peers turned away because [`MAX_PEERS`] others were alive.
    pub peers_refused: u64,
    /// Frames not written because a stream's queue was full (a reader that stopped reading).
    pub frames_dropped: u64,
}

/// The file (frames sent and received, `.tlog`) and its first error.
#[derive(Default)]
struct Log {
    file: Option<std::io::BufWriter<File>>,
    error: Option<std::io::Error>,
}

impl Log {
    fn frame(&mut self, frame: &[u8]) {
        if self.error.is_some() {
            return;
        }
        if let Some(l) = self.file.as_mut() {
            let us = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_micros() as u64);
            if let Err(e) = l
                .write_all(&us.to_be_bytes())
                .and_then(|_| l.write_all(frame))
            {
                self.error = Some(e);
            }
        }
    }
}

/// A UDP peer and when it last sent a valid frame.
struct UdpPeer {
    addr: SocketAddr,
    last: Instant,
}

/// A byte stream (a TCP connection or a serial port): its reader (the `mavlink` crate's, which
/// keeps a frame split across reads), the bytes waiting to go out, and when it last sent a
/// valid frame.
struct Stream<S> {
    reader: MavlinkReader<S>,
    out: Vec<u8>,
    /// When it last sent a valid frame (or connected, before its first).
    last: Instant,
    /// Whether it has sent a valid frame.
    heard: bool,
    /// A socket (written with `MSG_NOSIGNAL`: a closed peer is an error, never a `SIGPIPE`).
    socket: bool,
}

impl<S: Read + AsRawFd> Stream<S> {
    fn new(source: S, socket: bool) -> Self {
        Self {
            reader: MavlinkReader::new(source),
            out: Vec::new(),
            last: Instant::now(),
            heard: false,
            socket,
        }
    }

    fn fd(&self) -> RawFd {
        self.reader.get_ref().as_raw_fd()
    }

    /// Whether it is still a peer: heard within `timeout`, or, never heard, connected within
    /// [`HANDSHAKE_TIMEOUT`] (and `timeout`).
    fn alive(&self, timeout: Duration) -> bool {
        let limit = if self.heard {
            timeout
        } else {
            timeout.min(HANDSHAKE_TIMEOUT)
        };
        self.last.elapsed() <= limit
    }

    /// Queues `frame` whole, or drops it if the queue is full; `false` when dropped.
    fn queue(&mut self, frame: &[u8]) -> bool {
        if self.out.len() + frame.len() > MAX_QUEUED_BYTES {
            return false;
        }
        self.out.extend_from_slice(frame);
        true
    }

    /// Writes what the stream takes now; an error: the stream is broken.
    fn flush(&mut self) -> std::io::Result<()> {
        while !self.out.is_empty() {
            let fd = self.fd();
            let p = self.out.as_ptr() as *const libc::c_void;
            // SAFETY: `p` points to `self.out.len()` initialised bytes; `fd` is open (owned by
            // the reader's source).
            let n = unsafe {
                if self.socket {
                    libc::send(fd, p, self.out.len(), libc::MSG_NOSIGNAL)
                } else {
                    libc::write(fd, p, self.out.len())
                }
            };
            if n < 0 {
                let e = std::io::Error::last_os_error();
                match e.kind() {
                    std::io::ErrorKind::WouldBlock => return Ok(()),
                    std::io::ErrorKind::Interrupted => continue,
                    _ => return Err(e),
                }
            }
            self.out.drain(..n as usize);
        }
        Ok(())
    }
}

/// What the link is made of.
enum Kind {
    Udp {
        socket: UdpSocket,
        /// Where to write.
        peers: Vec<UdpPeer>,
        /// `udpout:`: the one peer, never dropped.
        fixed: bool,
    },
    TcpIn {
        listener: TcpListener,
        clients: Vec<Stream<TcpStream>>,
    },
    TcpOut {
        addr: SocketAddr,
        conn: Option<Stream<TcpStream>>,
        /// When to try again after the connection dropped.
        retry_at: Instant,
    },
    Serial {
        port: Option<Stream<File>>,
        device: String,
    },
}

/// One MAVLink 2 link.
pub struct Link {
    kind: Kind,
    system_id: u8,
    component_id: u8,
    sequence: u8,
    peer_timeout: Duration,
    log: Log,
    buf: Vec<u8>,
    /// The last [`RECENT_SENT`] frames sent: sequence number and message (an echo of them is
    /// this link's own frames coming back, not a twin's).
    recent_sent: std::collections::VecDeque<(u8, MavMessage)>,
    /// Counters.
    pub stats: LinkStats,
}

/// The frames sent that [`Link::is_own_echo`] recognises.
pub const RECENT_SENT: usize = 256;

/// Resolves `HOST:PORT`: no port, an empty host or port, a port outside [0, 65535] or a
/// host that names no address is a [`LinkError::Address`] (a usage error).
pub fn resolve(addr: &str) -> Result<SocketAddr, LinkError> {
    let Some((host, port)) = addr.rsplit_once(':') else {
        return Err(LinkError::Address(format!(
            "`{addr}` has no port (expected HOST:PORT)"
        )));
    };
    if host.is_empty() || port.is_empty() {
        return Err(LinkError::Address(format!(
            "`{addr}`: expected HOST:PORT, both given"
        )));
    }
    if port.parse::<u16>().is_err() {
        return Err(LinkError::Address(format!(
            "`{addr}`: the port `{port}` is not a number in [0, 65535]"
        )));
    }
    addr.to_socket_addrs()
        .map_err(|e| LinkError::Address(format!("cannot resolve `{addr}`: {e}")))?
        .next()
        .ok_or_else(|| LinkError::Address(format!("`{addr}` names no address")))
}

/// The termios speed of a baud rate.
fn speed_of(baud: u32) -> Option<libc::speed_t> {
    Some(match baud {
        110 => libc::B110,
        150 => libc::B150,
        300 => libc::B300,
        600 => libc::B600,
        1200 => libc::B1200,
        1800 => libc::B1800,
        2400 => libc::B2400,
        4800 => libc::B4800,
        9600 => libc::B9600,
        19200 => libc::B19200,
        38400 => libc::B38400,
        57600 => libc::B57600,
        115200 => libc::B115200,
        230400 => libc::B230400,
        460800 => libc::B460800,
        500000 => libc::B500000,
        576000 => libc::B576000,
        921600 => libc::B921600,
        1000000 => libc::B1000000,
        1152000 => libc::B1152000,
        1500000 => libc::B1500000,
        2000000 => libc::B2000000,
        2500000 => libc::B2500000,
        3000000 => libc::B3000000,
        3500000 => libc::B3500000,
        4000000 => libc::B4000000,
        _ => return None,
    })
}

/// Splits `serial:DEVICE:BAUD`'s rest into the device and its termios speed.
fn parse_serial(url: &str, rest: &str) -> Result<(String, u32), LinkError> {
    let Some((device, baud)) = rest.rsplit_once(':') else {
        return Err(LinkError::Address(format!(
            "`{url}`: expected serial:DEVICE:BAUD (serial:/dev/ttyUSB0:57600)"
        )));
    };
    if device.is_empty() {
        return Err(LinkError::Address(format!(
            "`{url}`: no device (expected serial:DEVICE:BAUD)"
        )));
    }
    let list = BAUD_RATES.map(|r| r.to_string()).join(", ");
    match baud.parse::<u32>().ok().filter(|b| speed_of(*b).is_some()) {
        Some(b) => Ok((device.to_string(), b)),
        None => Err(LinkError::Address(format!(
            "`{url}`: baud rate `{baud}` is not one of {list}"
        ))),
    }
}

/// Opens a serial device: a terminal device (refused otherwise, before and after opening), in
/// raw 8N1 mode at `baud`, non-blocking.
fn open_serial(url: &str, device: &str, baud: u32) -> Result<File, LinkError> {
    use std::os::unix::fs::FileTypeExt;
    let not_tty = |what: &str| {
        LinkError::Device(format!(
            "{url}: `{device}` is {what}, not a serial port (a terminal device such as /dev/ttyUSB0)"
        ))
    };
    let m = std::fs::metadata(device)
        .map_err(|e| LinkError::Device(format!("{url}: cannot open `{device}`: {e}")))?;
    let t = m.file_type();
    if !t.is_char_device() {
        return Err(not_tty(if t.is_fifo() {
            "a FIFO"
        } else if t.is_dir() {
            "a directory"
        } else if t.is_file() {
            "a regular file"
        } else if t.is_socket() {
            "a socket"
        } else {
            "a block device"
        }));
    }
    let c = std::ffi::CString::new(device)
        .map_err(|_| LinkError::Address(format!("{url}: the device name holds a NUL byte")))?;
    // SAFETY: `c` is a NUL-terminated path; the flags never block (O_NONBLOCK) nor make the
    // device our controlling terminal (O_NOCTTY).
    let fd = unsafe {
        libc::open(
            c.as_ptr(),
            libc::O_RDWR | libc::O_NOCTTY | libc::O_NONBLOCK | libc::O_CLOEXEC,
        )
    };
    if fd < 0 {
        let e = std::io::Error::last_os_error();
        return Err(LinkError::Device(format!(
            "{url}: cannot open `{device}`: {e}"
        )));
    }
    // SAFETY: `fd` was just opened and is owned by nobody else.
    let file = unsafe { File::from_raw_fd(fd) };
    // What was opened is what was checked (the path may have changed in between).
    let m = file
        .metadata()
        .map_err(|e| LinkError::Device(format!("{url}: `{device}`: {e}")))?;
    if !m.file_type().is_char_device() {
        return Err(not_tty("no longer a character device"));
    }
    // SAFETY: `t` is a plain C struct filled by tcgetattr before use.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: `fd` is open; `t` is a valid termios to fill.
    if unsafe { libc::tcgetattr(fd, &mut t) } != 0 {
        return Err(not_tty("a character device that is not a terminal"));
    }
    let speed = speed_of(baud).unwrap_or(libc::B57600);
    // SAFETY: `t` came from tcgetattr; cfmakeraw and cfset*speed only edit it.
    let ok = unsafe {
        libc::cfmakeraw(&mut t);
        libc::cfsetispeed(&mut t, speed) == 0 && libc::cfsetospeed(&mut t, speed) == 0
    };
    t.c_cflag |= libc::CLOCAL | libc::CREAD;
    t.c_cflag &= !(libc::CSTOPB | libc::CRTSCTS);
    // VMIN 1: with O_NONBLOCK an empty port reads as EAGAIN (VMIN 0 would read as 0 bytes,
    // an end of file).
    t.c_cc[libc::VMIN] = 1;
    t.c_cc[libc::VTIME] = 0;
    // SAFETY: `fd` is open; `t` is a valid termios.
    if !ok || unsafe { libc::tcsetattr(fd, libc::TCSANOW, &t) } != 0 {
        let e = std::io::Error::last_os_error();
        return Err(LinkError::Io(format!(
            "{url}: cannot set `{device}` to {baud} baud: {e}"
        )));
    }
    Ok(file)
}

fn connect(addr: SocketAddr, timeout: Duration) -> std::io::Result<Stream<TcpStream>> {
    let s = TcpStream::connect_timeout(&addr, timeout)?;
    s.set_nonblocking(true)?;
    // Lockstep sends one small frame and waits for the answer: no Nagle delay.
    s.set_nodelay(true)?;
    Ok(Stream::new(s, true))
}

/// Queues `frame` on a stream (counted in `dropped` if its queue is full) and writes what it
/// takes; `false` when the stream is broken.
fn put<S: Read + AsRawFd>(s: &mut Stream<S>, frame: &[u8], dropped: &mut u64) -> bool {
    if !s.queue(frame) {
        *dropped += 1;
    }
    s.flush().is_ok()
}

/// Reads the frames a stream has (at most [`MAX_FRAMES_PER_POLL`]); `false` when it is closed
/// or broken (a serial port's read of 0 bytes is no end: nothing came).
fn drain<S: Read>(
    s: &mut Stream<S>,
    stats: &mut LinkStats,
    log: &mut Log,
    out: &mut Vec<Received>,
) -> bool {
    for _ in 0..MAX_FRAMES_PER_POLL {
        match s.reader.read_any_raw_message::<MavMessage>() {
            Ok(raw) => {
                if accept(raw, stats, log, out) {
                    s.last = Instant::now();
                    s.heard = true;
                }
            }
            Err(MessageReadError::Io(e)) if e.kind() == std::io::ErrorKind::WouldBlock => {
                return true
            }
            Err(MessageReadError::Io(e))
                if !s.socket && e.kind() == std::io::ErrorKind::UnexpectedEof =>
            {
                return true
            }
            // End of file (the peer closed) or an error: the stream is gone.
            Err(MessageReadError::Io(_)) => return false,
            Err(MessageReadError::Parse(_)) => {}
        }
    }
    true
}

/// Takes a raw frame that passed its checksum: a MAVLink 2 message of the common dialect goes
/// to `out` (`true`); MAVLink 1 is counted and dropped.
fn accept(
    raw: MAVLinkMessageRaw,
    stats: &mut LinkStats,
    log: &mut Log,
    out: &mut Vec<Received>,
) -> bool {
    let raw = match raw {
        MAVLinkMessageRaw::V2(raw) => raw,
        MAVLinkMessageRaw::V1(_) => {
            stats.mavlink1_frames += 1;
            return false;
        }
    };
    let Ok(msg) = MavMessage::parse(MavlinkVersion::V2, raw.message_id(), raw.payload()) else {
        return false;
    };
    let ack_target = matches!(msg, MavMessage::COMMAND_ACK(_)).then(|| {
        let p = raw.payload();
        (
            p.get(8).copied().unwrap_or(0),
            p.get(9).copied().unwrap_or(0),
        )
    });
    log.frame(raw.raw_bytes());
    stats.frames_in += 1;
    out.push(Received {
        header: MavHeader {
            system_id: raw.system_id(),
            component_id: raw.component_id(),
            sequence: raw.sequence(),
        },
        msg,
        from: None,
        ack_target,
    });
    true
}

/// Whether `datagram` is one or more whole MAVLink 2 frames, back to back, each of a message
/// outside the common dialect: a start byte 0xFD, a header of 10 bytes, the payload its length
/// byte says, a 2-byte checksum and, when its incompatibility flags say signed, a 13-byte
/// signature; nothing before, between or after. Such frames are another dialect's (valid, for
/// all that can be checked here), not junk.
fn only_other_dialect_frames(datagram: &[u8]) -> bool {
    let mut at = 0;
    while at < datagram.len() {
        let Some(h) = datagram.get(at..at + 10) else {
            return false;
        };
        if h[0] != 0xFD {
            return false;
        }
        let id = u32::from_le_bytes([h[7], h[8], h[9], 0]);
        if <MavMessage as mavlink::Message>::default_message_from_id(id).is_some() {
            return false;
        }
        let signed = h[2] & 0x01 != 0;
        at += 12 + h[1] as usize + if signed { 13 } else { 0 };
    }
    at == datagram.len() && !datagram.is_empty()
}

/// Waits until one of `fds` is readable or `timeout` passes (`poll(2)`).
fn wait_readable(fds: &[RawFd], timeout: Duration) -> std::io::Result<()> {
    let mut p: Vec<libc::pollfd> = fds
        .iter()
        .map(|&fd| libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        })
        .collect();
    let ms = timeout.as_millis().clamp(0, i32::MAX as u128) as libc::c_int;
    // SAFETY: `p` holds `p.len()` valid pollfd structs.
    let r = unsafe { libc::poll(p.as_mut_ptr(), p.len() as libc::nfds_t, ms) };
    if r < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
    Ok(())
}

impl Kind {
    /// The transport `url` names, opened (bound, listening, connected or the device opened).
    fn open(url: &str) -> Result<Self, LinkError> {
        let kinds = "udpin:HOST:PORT, udpout:HOST:PORT, tcpin:HOST:PORT, tcpout:HOST:PORT or serial:DEVICE:BAUD";
        let (mode, rest) = url
            .split_once(':')
            .ok_or_else(|| LinkError::Address(format!("`{url}`: expected {kinds}")))?;
        let rest = rest.strip_prefix("//").unwrap_or(rest);
        let io = |e: std::io::Error| LinkError::Io(format!("{url}: {e}"));
        // A port another process listens on (a second `fly` or `sitl` on one `udpin:` port):
        // refused, never shared (no SO_REUSEADDR/SO_REUSEPORT), and said so.
        let bind_err = |e: std::io::Error| {
            if e.kind() == std::io::ErrorKind::AddrInUse {
                LinkError::Io(format!(
                    "{url}: the port is taken: another process (a second `fly` or `sitl`?) listens on it, and a port is never shared ({e})"
                ))
            } else {
                io(e)
            }
        };
        Ok(match mode {
            "udpin" => Kind::Udp {
                socket: UdpSocket::bind(resolve(rest)?).map_err(bind_err)?,
                peers: Vec::new(),
                fixed: false,
            },
            "udpout" => {
                let a = resolve(rest)?;
                let local: SocketAddr = if a.is_ipv4() {
                    "0.0.0.0:0".parse().expect("an address")
                } else {
                    "[::]:0".parse().expect("an address")
                };
                Kind::Udp {
                    socket: UdpSocket::bind(local).map_err(io)?,
                    peers: vec![UdpPeer {
                        addr: a,
                        last: Instant::now(),
                    }],
                    fixed: true,
                }
            }
            "tcpin" => {
                let listener = TcpListener::bind(resolve(rest)?).map_err(bind_err)?;
                listener.set_nonblocking(true).map_err(io)?;
                Kind::TcpIn {
                    listener,
                    clients: Vec::new(),
                }
            }
            "tcpout" => {
                let a = resolve(rest)?;
                let conn = connect(a, Duration::from_secs(5)).map_err(|e| {
                    LinkError::Unavailable(format!("{url}: cannot connect to {a}: {e}"))
                })?;
                Kind::TcpOut {
                    addr: a,
                    conn: Some(conn),
                    retry_at: Instant::now(),
                }
            }
            "serial" => {
                let (device, baud) = parse_serial(url, rest)?;
                Kind::Serial {
                    port: Some(Stream::new(open_serial(url, &device, baud)?, false)),
                    device: format!("{device} at {baud} baud"),
                }
            }
            _ => {
                return Err(LinkError::Address(format!(
                    "`{url}`: unknown link kind `{mode}` (expected {kinds})"
                )))
            }
        })
    }
}

impl Link {
    /// Opens `url` as system `system_id`, component `component_id`.
    pub fn open(url: &str, system_id: u8, component_id: u8) -> Result<Self, LinkError> {
        Ok(Self {
            kind: Kind::open(url)?,
            system_id,
            component_id,
            sequence: 0,
            peer_timeout: DEFAULT_PEER_TIMEOUT,
            log: Log::default(),
            buf: vec![0; 65_536],
            recent_sent: std::collections::VecDeque::new(),
            stats: LinkStats::default(),
        })
    }

    /// The local address (the port a `udpin:HOST:0` or `tcpin:HOST:0` link was given); an
    /// error for a serial link, which has none.
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        match &self.kind {
            Kind::Udp { socket, .. } => socket.local_addr(),
            Kind::TcpIn { listener, .. } => listener.local_addr(),
            Kind::TcpOut { conn: Some(c), .. } => c.reader.get_ref().local_addr(),
            Kind::TcpOut { conn: None, .. } => Err(std::io::Error::new(
                std::io::ErrorKind::NotConnected,
                "the TCP connection dropped",
            )),
            Kind::Serial { .. } => Err(std::io::Error::new(
                std::io::ErrorKind::Unsupported,
                "a serial link has no network address",
            )),
        }
    }

    /// Where the link is, for messages: the local socket address, or the serial device and
    /// its baud rate.
    pub fn describe(&self) -> String {
        match &self.kind {
            Kind::Serial { device, .. } => device.clone(),
            _ => self
                .local_addr()
                .map_or_else(|e| e.to_string(), |a| a.to_string()),
        }
    }

    /// Whether the link knows where to write (a `udpin:` link once someone has written to it,
    /// a `tcpin:` link once a client is connected).
    pub fn has_peer(&self) -> bool {
        self.peer_count() > 0
    }

    /// How many peers the link writes to (at most [`MAX_PEERS`]).
    pub fn peer_count(&self) -> usize {
        match &self.kind {
            Kind::Udp { peers, .. } => peers.len(),
            Kind::TcpIn { clients, .. } => clients.len(),
            Kind::TcpOut { conn, .. } => usize::from(conn.is_some()),
            Kind::Serial { port, .. } => usize::from(port.is_some()),
        }
    }

    /// Sets how long a peer of a `udpin:` or `tcpin:` link may be silent (no valid frame)
    /// before it is dropped.
    pub fn set_peer_timeout(&mut self, timeout: Duration) {
        self.peer_timeout = timeout;
    }

    /// Logs every frame sent and received into `path` as a telemetry log (`.tlog`: each frame
    /// after its time, microseconds since the Unix epoch, big-endian `u64`), the format
    /// QGroundControl, MAVProxy and pymavlink read.
    /// An existing `path` that is not a regular file (a symbolic link, a FIFO) is refused, never
    /// written through nor waited on (`O_NOFOLLOW | O_NONBLOCK`, then checked).
    pub fn log_to(&mut self, path: &Path) -> std::io::Result<()> {
        let refuse = || {
            std::io::Error::other(format!(
                "{} exists and is not a regular file (a link, FIFO, directory or device): refusing to write it",
                path.display()
            ))
        };
        if matches!(std::fs::symlink_metadata(path), Ok(m) if !m.file_type().is_file()) {
            return Err(refuse());
        }
        let mut o = std::fs::OpenOptions::new();
        o.write(true).create(true).truncate(false);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            o.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
        }
        let f: File = o.open(path)?;
        if !f.metadata()?.is_file() {
            return Err(refuse());
        }
        f.set_len(0)?;
        self.log.file = Some(std::io::BufWriter::new(f));
        Ok(())
    }

    /// Whether `r` is one of this link's own last [`RECENT_SENT`] frames come back (a routing
    /// loop, a broadcast set-up that hands the sender its own datagrams): its ids, sequence
    /// number and message those of a frame it sent.
    pub fn is_own_echo(&self, r: &Received) -> bool {
        r.header.system_id == self.system_id.into()
            && r.header.component_id == self.component_id
            && self
                .recent_sent
                .iter()
                .any(|(seq, m)| *seq == r.header.sequence && *m == r.msg)
    }

    /// The first error met while writing the log (a full disk), if any: from then on no frame
    /// is written to it (ver33-6).
    pub fn log_error(&self) -> Option<&std::io::Error> {
        self.log.error.as_ref()
    }

    /// Flushes the log; the first error met while writing it, if any.
    pub fn finish_log(&mut self) -> std::io::Result<()> {
        if let Some(e) = self.log.error.take() {
            return Err(e);
        }
        match self.log.file.as_mut() {
            Some(l) => l.flush(),
            None => Ok(()),
        }
    }

    /// Drops the peers silent for longer than the peer timeout (and streams that closed).
    fn evict(&mut self) {
        let timeout = self.peer_timeout;
        let before = self.peer_count();
        match &mut self.kind {
            Kind::Udp {
                peers,
                fixed: false,
                ..
            } => peers.retain(|p| p.last.elapsed() <= timeout),
            Kind::TcpIn { clients, .. } => clients.retain(|c| c.alive(timeout)),
            _ => {}
        }
        self.stats.peers_evicted += before.saturating_sub(self.peer_count()) as u64;
    }

    /// Sends `msg` (MAVLink 2) to the peers; `Ok(false)` if there is no peer yet.
    pub fn send(&mut self, msg: &MavMessage) -> std::io::Result<bool> {
        self.send_with(msg, None)
    }

    /// As [`Link::send`], with the bytes of the message's MAVLink 2 extension fields, which the
    /// `mavlink` crate's common dialect (built without its `mav2-message-extensions` feature)
    /// leaves out: `extensions` after the `base_len` bytes of its own fields, the checksum
    /// seeded with `extra_crc` ([`crate::wire::extend_v2_frame`]).
    pub fn send_extended(
        &mut self,
        msg: &MavMessage,
        extra_crc: u8,
        base_len: usize,
        extensions: &[u8],
    ) -> std::io::Result<bool> {
        self.send_with(msg, Some((extra_crc, base_len, extensions)))
    }

    fn send_with(
        &mut self,
        msg: &MavMessage,
        extensions: Option<(u8, usize, &[u8])>,
    ) -> std::io::Result<bool> {
        self.evict();
        if !self.has_peer() {
            return Ok(false);
        }
        let header = MavHeader {
            system_id: self.system_id.into(),
            component_id: self.component_id,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        if self.recent_sent.len() == RECENT_SENT {
            self.recent_sent.pop_front();
        }
        self.recent_sent.push_back((header.sequence, msg.clone()));
        let mut frame = Vec::with_capacity(300);
        mavlink::write_v2_msg(&mut frame, header, msg).map_err(std::io::Error::other)?;
        if let Some((extra_crc, base_len, ext)) = extensions {
            frame = crate::wire::extend_v2_frame(&frame, extra_crc, base_len, ext);
        }
        self.log.frame(&frame);
        self.stats.frames_out += 1;
        let stats = &mut self.stats;
        match &mut self.kind {
            Kind::Udp { socket, peers, .. } => {
                for peer in peers.iter() {
                    match socket.send_to(&frame, peer.addr) {
                        Ok(_) => {}
                        // Nobody listening (ICMP port unreachable comes back as this on
                        // Linux), or the socket buffer full under a flood: UDP carries on.
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::ConnectionRefused
                                    | std::io::ErrorKind::WouldBlock
                            ) => {}
                        Err(e) => return Err(e),
                    }
                }
            }
            Kind::TcpIn { clients, .. } => {
                let before = clients.len();
                clients.retain_mut(|c| put(c, &frame, &mut stats.frames_dropped));
                stats.peers_evicted += (before - clients.len()) as u64;
            }
            Kind::TcpOut { conn, .. } => {
                if conn
                    .as_mut()
                    .is_some_and(|c| !put(c, &frame, &mut stats.frames_dropped))
                {
                    *conn = None;
                    stats.peers_evicted += 1;
                }
            }
            Kind::Serial { port, .. } => {
                if port
                    .as_mut()
                    .is_some_and(|p| !put(p, &frame, &mut stats.frames_dropped))
                {
                    *port = None;
                }
            }
        }
        Ok(true)
    }

    /// Reads what arrives within `timeout` (at least one datagram's or read's worth if any
    /// comes, then whatever else is already there, up to [`MAX_DATAGRAMS_PER_POLL`] datagrams
    /// or [`MAX_FRAMES_PER_POLL`] frames a stream).
    pub fn poll(&mut self, timeout: Duration) -> std::io::Result<Vec<Received>> {
        self.evict();
        if matches!(self.kind, Kind::Udp { .. }) {
            return self.poll_udp(timeout);
        }
        let mut out = Vec::new();
        self.poll_streams(&mut out)?;
        if out.is_empty() {
            let fds = self.fds();
            if fds.is_empty() {
                std::thread::sleep(timeout);
            } else {
                wait_readable(&fds, timeout)?;
            }
            self.poll_streams(&mut out)?;
        }
        Ok(out)
    }

    /// The descriptors a stream link waits on.
    fn fds(&self) -> Vec<RawFd> {
        match &self.kind {
            Kind::Udp { socket, .. } => vec![socket.as_raw_fd()],
            Kind::TcpIn { listener, clients } => std::iter::once(listener.as_raw_fd())
                .chain(clients.iter().map(|c| c.fd()))
                .collect(),
            Kind::TcpOut { conn, .. } => conn.iter().map(|c| c.fd()).collect(),
            Kind::Serial { port, .. } => port.iter().map(|p| p.fd()).collect(),
        }
    }

    /// One non-blocking pass over a stream link: new connections, queued bytes, frames.
    fn poll_streams(&mut self, out: &mut Vec<Received>) -> std::io::Result<()> {
        let (stats, log, timeout) = (&mut self.stats, &mut self.log, self.peer_timeout);
        match &mut self.kind {
            Kind::Udp { .. } => {}
            Kind::TcpIn { listener, clients } => {
                // New clients: a free place, or a silent client's, or the place of one never
                // heard that connected before this pass (one accepted now has had no time to
                // speak); else turned away.
                let pass_start = Instant::now();
                for _ in 0..4 * MAX_PEERS {
                    let (s, _) = match listener.accept() {
                        Ok(x) => x,
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::Interrupted
                                    | std::io::ErrorKind::ConnectionAborted
                                    | std::io::ErrorKind::ConnectionReset
                            ) =>
                        {
                            continue
                        }
                        // Out of descriptors and the like: no new client this time.
                        Err(_) => break,
                    };
                    if clients.len() == MAX_PEERS {
                        // A silent client's place, else the oldest never heard (its frames
                        // would have come by now if it spoke MAVLink).
                        let silent = clients.iter().position(|c| !c.alive(timeout));
                        let unheard = || {
                            (0..clients.len())
                                .filter(|&i| !clients[i].heard && clients[i].last < pass_start)
                                .min_by_key(|&i| clients[i].last)
                        };
                        if let Some(i) = silent.or_else(unheard) {
                            clients.remove(i);
                            stats.peers_evicted += 1;
                        }
                    }
                    if clients.len() == MAX_PEERS
                        || s.set_nonblocking(true).is_err()
                        || s.set_nodelay(true).is_err()
                    {
                        stats.peers_refused += 1;
                        continue;
                    }
                    clients.push(Stream::new(s, true));
                }
                let before = clients.len();
                clients.retain_mut(|c| c.flush().is_ok() && drain(c, stats, log, out));
                stats.peers_evicted += (before - clients.len()) as u64;
            }
            Kind::TcpOut {
                addr,
                conn,
                retry_at,
            } => {
                if conn.is_none() && Instant::now() >= *retry_at {
                    *retry_at = Instant::now() + Duration::from_secs(1);
                    *conn = connect(*addr, Duration::from_millis(100)).ok();
                }
                if let Some(c) = conn.as_mut() {
                    if !(c.flush().is_ok() && drain(c, stats, log, out)) {
                        *conn = None;
                        stats.peers_evicted += 1;
                        *retry_at = Instant::now() + Duration::from_secs(1);
                    }
                }
            }
            Kind::Serial { port, .. } => {
                if let Some(p) = port.as_mut() {
                    if !(p.flush().is_ok() && drain(p, stats, log, out)) {
                        *port = None;
                    }
                }
            }
        }
        Ok(())
    }

    fn poll_udp(&mut self, timeout: Duration) -> std::io::Result<Vec<Received>> {
        let mut out = Vec::new();
        let Kind::Udp {
            socket,
            peers,
            fixed,
        } = &mut self.kind
        else {
            return Ok(out);
        };
        let timeout = timeout.max(Duration::from_micros(100));
        socket.set_read_timeout(Some(timeout))?;
        socket.set_nonblocking(false)?;
        for i in 0..MAX_DATAGRAMS_PER_POLL {
            if i == 1 {
                socket.set_nonblocking(true)?;
            }
            let (n, from) = match socket.recv_from(&mut self.buf) {
                Ok(x) => x,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::ConnectionRefused
                            | std::io::ErrorKind::Interrupted
                    ) =>
                {
                    break
                }
                Err(e) => return Err(e),
            };
            self.stats.datagrams += 1;
            let before = out.len();
            let datagram = &self.buf[..n];
            let mut reader = MavlinkReader::new(datagram);
            // A datagram of n bytes holds at most n / 12 frames (the smallest MAVLink 2 frame).
            for _ in 0..=n / 12 {
                match reader.read_any_raw_message::<MavMessage>() {
                    Ok(raw) => {
                        accept(raw, &mut self.stats, &mut self.log, &mut out);
                    }
                    Err(_) => break,
                }
            }
            if out.len() == before {
                if only_other_dialect_frames(datagram) {
                    self.stats.other_dialect_datagrams += 1;
                } else {
                    self.stats.junk_datagrams += 1;
                }
                continue;
            }
            for r in &mut out[before..] {
                r.from = Some(from);
            }
            if !*fixed {
                note_peer(peers, from, self.peer_timeout, &mut self.stats);
            }
        }
        socket.set_nonblocking(false)?;
        Ok(out)
    }
}

/// A `udpin:` link's peers after a valid frame from `from`: a known peer's time renewed; a new
/// one takes a free place, or the place of one silent for `peer_timeout`; while [`MAX_PEERS`]
/// others are talking, it is turned away (its frames are still read): a flood of spoofed
/// addresses cannot push out the live peers.
fn note_peer(
    peers: &mut Vec<UdpPeer>,
    from: SocketAddr,
    peer_timeout: Duration,
    stats: &mut LinkStats,
) {
    let now = Instant::now();
    if let Some(p) = peers.iter_mut().find(|p| p.addr == from) {
        p.last = now;
        return;
    }
    if peers.len() == MAX_PEERS {
        if let Some(i) = peers
            .iter()
            .position(|p| now.duration_since(p.last) > peer_timeout)
        {
            peers.remove(i);
            stats.peers_evicted += 1;
        }
    }
    if peers.len() < MAX_PEERS {
        peers.push(UdpPeer {
            addr: from,
            last: now,
        });
    } else {
        stats.peers_refused += 1;
    }
}

#[cfg(test)]
mod tests {
    /// ver33-6: a log whose disk is full (`/dev/full`: every write ENOSPC) keeps its first
    /// error, which `log_error` reports and `finish_log` returns, and writes nothing more.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_full_disk_stops_the_log_and_says_so() {
        let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        link.log.file = Some(std::io::BufWriter::new(f));
        assert!(link.log_error().is_none());
        // More than the writer's 8 KiB buffer: the write reaches the device.
        for _ in 0..200 {
            link.log.frame(&[0u8; 100]);
        }
        let e = link.log_error().expect("the full disk's error");
        assert_eq!(e.raw_os_error(), Some(libc::ENOSPC));
        assert!(link.finish_log().is_err());
    }

    use super::*;

    fn address_error(url: &str) -> String {
        match Link::open(url, 1, 1) {
            Err(LinkError::Address(m)) => m,
            Err(e) => panic!("{url}: not a usage error: {e}"),
            Ok(_) => panic!("{url}: opened"),
        }
    }

    /// Unknown kinds, missing ports and baud rates are usage errors naming what was wrong.
    #[test]
    fn malformed_addresses_are_usage_errors() {
        assert!(address_error("ftp:127.0.0.1:1").contains("unknown link kind `ftp`"));
        assert!(address_error("127.0.0.1").contains("expected udpin:"));
        assert!(address_error("tcpin:127.0.0.1").contains("has no port"));
        assert!(address_error("tcpout://localhost:").contains("both given"));
        assert!(address_error("udpin:127.0.0.1:99999").contains("not a number in [0, 65535]"));
        assert!(address_error("serial:/dev/ttyS0").contains("expected serial:DEVICE:BAUD"));
        assert!(address_error("serial:/dev/ttyS0:56000").contains("57600"));
        assert!(address_error("serial::57600").contains("no device"));
    }

    /// att33c item 22: a datagram holding only well-formed frames of another dialect
    /// (ArduPilot's MEMINFO, id 152) is no junk: counted apart; one of damaged bytes or a frame
    /// of the common dialect with a broken checksum is junk.
    #[test]
    fn another_dialects_frames_are_not_junk() {
        let mut link = Link::open("udpin:127.0.0.1:0", 1, 191).unwrap();
        let to = link.local_addr().unwrap();
        let s = UdpSocket::bind("127.0.0.1:0").unwrap();
        // MEMINFO (152): 4-byte payload, any checksum (its CRC extra is not known here).
        let meminfo = [0xFD, 4, 0, 0, 7, 1, 1, 152, 0, 0, 1, 2, 3, 4, 0xAB, 0xCD];
        let two: Vec<u8> = meminfo.iter().chain(meminfo.iter()).copied().collect();
        // A heartbeat (id 0, common) with a broken checksum: junk.
        let heartbeat = [
            0xFD, 9, 0, 0, 7, 1, 1, 0, 0, 0, 0, 0, 0, 0, 1, 8, 0, 0, 3, 0, 0,
        ];
        for d in [&meminfo[..], &two, b"hello\n", &meminfo[..15], &heartbeat] {
            s.send_to(d, to).unwrap();
        }
        let t0 = Instant::now();
        while link.stats.datagrams < 5 && t0.elapsed() < Duration::from_secs(10) {
            link.poll(Duration::from_millis(50)).unwrap();
        }
        assert_eq!(link.stats.other_dialect_datagrams, 2, "{:?}", link.stats);
        assert_eq!(link.stats.junk_datagrams, 3, "{:?}", link.stats);
        assert!(!only_other_dialect_frames(&[]));
    }

    /// A serial device that is a regular file, a directory or missing is a device error.
    #[test]
    fn a_serial_device_must_be_a_terminal() {
        let dir = std::env::temp_dir().join(format!("isotrack-serial-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("plain");
        std::fs::write(&file, b"").unwrap();
        let fifo = dir.join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        for (p, what) in [
            (file.clone(), "a regular file"),
            (fifo.clone(), "a FIFO"),
            (dir.clone(), "a directory"),
            (dir.join("missing"), "No such file"),
            (std::path::PathBuf::from("/dev/null"), "not a terminal"),
        ] {
            let url = format!("serial:{}:57600", p.display());
            match Link::open(&url, 1, 1) {
                Err(LinkError::Device(m)) => assert!(m.contains(what), "{m}"),
                Err(e) => panic!("{url}: {e:?}"),
                Ok(_) => panic!("{url}: opened"),
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
