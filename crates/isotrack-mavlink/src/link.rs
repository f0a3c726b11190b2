//! A MAVLink 2 link over UDP: the `mavlink` crate frames, checks and parses every message (common
//! dialect); this module owns the socket, so that a test can bind port 0 and learn the port, a
//! loop can wait with a timeout, and every frame can be logged.
//!
//! Addresses (the `mavlink` crate's spelling): `udpin:HOST:PORT` listens on `HOST:PORT` and
//! writes to every address that sent it a valid frame (up to [`MAX_PEERS`], the longest silent
//! dropped first: a ground station and a companion at once, and a stranger's traffic does not
//! divert the link); `udpout:HOST:PORT` writes to `HOST:PORT` from a free local port.
//! (`udpin://` and `udpout://` are accepted too.)
//!
//! Hostile traffic: a datagram is read frame by frame; bytes that are not a MAVLink 2 frame with a
//! valid checksum are skipped (counted in [`LinkStats::junk_datagrams`] when a datagram yields
//! nothing), message ids outside the common dialect are dropped, and one call reads at most
//! [`MAX_DATAGRAMS_PER_POLL`] datagrams, so a flood delays a loop but never starves it.

use mavlink::dialects::common::MavMessage;
use mavlink::{MAVLinkMessageRaw, MavHeader, MavlinkReader, MavlinkVersion, Message as _};
use std::io::Write;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::path::Path;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// The most peers a `udpin:` link writes to.
pub const MAX_PEERS: usize = 8;

/// The most datagrams one [`Link::poll`] reads.
pub const MAX_DATAGRAMS_PER_POLL: usize = 256;

/// A link that cannot be opened.
#[derive(Debug)]
pub enum LinkError {
    /// The address is not one this bridge speaks (a usage error).
    Address(String),
    /// The socket cannot be had (an operating-system error).
    Io(String),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Address(m) | LinkError::Io(m) => f.write_str(m),
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
}

/// What the link has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Datagrams read.
    pub datagrams: u64,
    /// Datagrams without one valid frame of the common dialect.
    pub junk_datagrams: u64,
    /// Valid frames read.
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// MAVLink 1 frames (valid checksum) received and dropped: this bridge speaks MAVLink 2.
    pub mavlink1_frames: u64,
}

/// One UDP MAVLink 2 link.
pub struct Link {
    socket: UdpSocket,
    /// Where to write, most recently heard last.
    peers: Vec<SocketAddr>,
    fixed_peer: bool,
    system_id: u8,
    component_id: u8,
    sequence: u8,
    log: Option<std::io::BufWriter<std::fs::File>>,
    log_error: Option<std::io::Error>,
    buf: Vec<u8>,
    /// Counters.
    pub stats: LinkStats,
}

fn resolve(addr: &str) -> Result<SocketAddr, LinkError> {
    addr.to_socket_addrs()
        .map_err(|e| LinkError::Address(format!("cannot resolve `{addr}`: {e}")))?
        .next()
        .ok_or_else(|| LinkError::Address(format!("`{addr}` names no address")))
}

impl Link {
    /// Opens `url` as system `system_id`, component `component_id`.
    pub fn open(url: &str, system_id: u8, component_id: u8) -> Result<Self, LinkError> {
        let (mode, rest) = url.split_once(':').ok_or_else(|| {
            LinkError::Address(format!(
                "`{url}`: expected udpin:HOST:PORT or udpout:HOST:PORT"
            ))
        })?;
        let rest = rest.strip_prefix("//").unwrap_or(rest);
        let io = |e: std::io::Error| LinkError::Io(format!("{url}: {e}"));
        let (socket, peer, fixed_peer) = match mode {
            "udpin" => {
                let a = resolve(rest)?;
                (UdpSocket::bind(a).map_err(io)?, None, false)
            }
            "udpout" => {
                let a = resolve(rest)?;
                let local: SocketAddr = if a.is_ipv4() {
                    "0.0.0.0:0".parse().expect("an address")
                } else {
                    "[::]:0".parse().expect("an address")
                };
                (UdpSocket::bind(local).map_err(io)?, Some(a), true)
            }
            "tcpin" | "tcpout" | "serial" => {
                return Err(LinkError::Address(format!(
                    "`{url}`: only UDP links (udpin:, udpout:) are supported so far"
                )))
            }
            _ => {
                return Err(LinkError::Address(format!(
                    "`{url}`: unknown link kind `{mode}` (expected udpin:HOST:PORT or udpout:HOST:PORT)"
                )))
            }
        };
        Ok(Self {
            socket,
            peers: peer.into_iter().collect(),
            fixed_peer,
            system_id,
            component_id,
            sequence: 0,
            log: None,
            log_error: None,
            buf: vec![0; 65_536],
            stats: LinkStats::default(),
        })
    }

    /// The local address (the port a `udpin:HOST:0` link was given).
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Whether the link knows where to write (a `udpin:` link once someone has written to it).
    pub fn has_peer(&self) -> bool {
        !self.peers.is_empty()
    }

    /// Logs every frame sent and received into `path` as a telemetry log (`.tlog`: each frame
    /// after its time, microseconds since the Unix epoch, big-endian `u64`), the format
    /// QGroundControl, MAVProxy and pymavlink read.
    pub fn log_to(&mut self, path: &Path) -> std::io::Result<()> {
        self.log = Some(std::io::BufWriter::new(std::fs::File::create(path)?));
        Ok(())
    }

    /// Flushes the log; the first error met while writing it, if any.
    pub fn finish_log(&mut self) -> std::io::Result<()> {
        if let Some(e) = self.log_error.take() {
            return Err(e);
        }
        match self.log.as_mut() {
            Some(l) => l.flush(),
            None => Ok(()),
        }
    }

    fn log_frame(&mut self, frame: &[u8]) {
        if self.log_error.is_some() {
            return;
        }
        if let Some(l) = self.log.as_mut() {
            let us = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_micros() as u64);
            if let Err(e) = l
                .write_all(&us.to_be_bytes())
                .and_then(|_| l.write_all(frame))
            {
                self.log_error = Some(e);
            }
        }
    }

    /// Sends `msg` (MAVLink 2) to the peer; `Ok(false)` if there is no peer yet.
    pub fn send(&mut self, msg: &MavMessage) -> std::io::Result<bool> {
        if self.peers.is_empty() {
            return Ok(false);
        }
        let header = MavHeader {
            system_id: self.system_id.into(),
            component_id: self.component_id,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let mut frame = Vec::with_capacity(300);
        mavlink::write_v2_msg(&mut frame, header, msg).map_err(std::io::Error::other)?;
        self.log_frame(&frame);
        self.stats.frames_out += 1;
        for peer in &self.peers {
            match self.socket.send_to(&frame, peer) {
                Ok(_) => {}
                // Nobody listening (ICMP port unreachable comes back as this on Linux), or the
                // socket buffer full under a flood: UDP carries on.
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::ConnectionRefused | std::io::ErrorKind::WouldBlock
                    ) => {}
                Err(e) => return Err(e),
            }
        }
        Ok(true)
    }

    /// Reads what arrives within `timeout` (at least one datagram's worth if any comes, then
    /// whatever else is already there, up to [`MAX_DATAGRAMS_PER_POLL`] datagrams).
    pub fn poll(&mut self, timeout: Duration) -> std::io::Result<Vec<Received>> {
        let mut out = Vec::new();
        let timeout = timeout.max(Duration::from_micros(100));
        self.socket.set_read_timeout(Some(timeout))?;
        self.socket.set_nonblocking(false)?;
        for i in 0..MAX_DATAGRAMS_PER_POLL {
            if i == 1 {
                self.socket.set_nonblocking(true)?;
            }
            let (n, from) = match self.socket.recv_from(&mut self.buf) {
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
            let datagram = self.buf[..n].to_vec();
            self.read_frames(&datagram, &mut out);
            if out.len() == before {
                self.stats.junk_datagrams += 1;
            } else if !self.fixed_peer {
                self.peers.retain(|p| *p != from);
                if self.peers.len() == MAX_PEERS {
                    self.peers.remove(0);
                }
                self.peers.push(from);
            }
        }
        self.socket.set_nonblocking(false)?;
        Ok(out)
    }

    fn read_frames(&mut self, datagram: &[u8], out: &mut Vec<Received>) {
        let mut reader = MavlinkReader::new(datagram);
        // A datagram of n bytes holds at most n / 12 frames (the smallest MAVLink 2 frame).
        for _ in 0..=datagram.len() / 12 {
            let raw = match reader.read_any_raw_message::<MavMessage>() {
                Ok(MAVLinkMessageRaw::V2(raw)) => raw,
                Ok(MAVLinkMessageRaw::V1(_)) => {
                    self.stats.mavlink1_frames += 1;
                    continue;
                }
                Err(_) => break,
            };
            let Ok(msg) = MavMessage::parse(MavlinkVersion::V2, raw.message_id(), raw.payload())
            else {
                continue;
            };
            self.log_frame(raw.raw_bytes());
            self.stats.frames_in += 1;
            out.push(Received {
                header: MavHeader {
                    system_id: raw.system_id(),
                    component_id: raw.component_id(),
                    sequence: raw.sequence(),
                },
                msg,
            });
        }
    }
}
