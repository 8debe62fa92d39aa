//! SocketCAN I/O (feature `socket`): a thin typed layer over `socketcan` 4.
//!
//! - non-blocking reads ([`BusSocket::recv`] returns `Ok(None)` when nothing is queued), so the
//!   ECU cycle can drain the socket without ever sleeping in the kernel;
//! - kernel id filters, so a process only wakes for the frames it consumes;
//! - error frames are requested from the kernel and counted, never handed to the decoder;
//! - receive timestamps: the kernel's `SO_TIMESTAMPNS` arrival time (CLOCK_REALTIME, set when the
//!   frame entered the socket layer) plus a CLOCK_MONOTONIC reading taken right after the read,
//!   for latency measurements that must not jump with wall-clock steps.
//!
//! Nothing here allocates after [`BusSocket::open`].

use std::io;
use std::time::{Instant, SystemTime};

use socketcan::{
    CanDataFrame, CanFilter, CanFrame, CanSocket, EmbeddedFrame, Frame, Socket, SocketOptions,
};

use crate::{RawFrame, CAN_EFF_FLAG};

/// Linux `CAN_SFF_MASK`: the 11 identifier bits.
const CAN_SFF_MASK: u32 = 0x7FF;
/// Linux `CAN_RTR_FLAG`.
const CAN_RTR_FLAG: u32 = 0x4000_0000;

/// The CAN interface a bench process opens: `flag` (its `--can`), else `$VCAN` (what
/// `./vcan-setup.sh` exports), else `vcan0`.
pub fn interface(flag: Option<&str>) -> String {
    flag.map(str::to_owned)
        .or_else(|| std::env::var("VCAN").ok().filter(|v| !v.is_empty()))
        .unwrap_or_else(|| "vcan0".to_owned())
}

/// A received data frame with its timestamps.
#[derive(Debug, Clone, Copy)]
pub struct RxFrame {
    /// The frame.
    pub frame: RawFrame,
    /// Kernel receive time (`SO_TIMESTAMPNS`), `None` if the kernel did not provide one.
    pub kernel_time: Option<SystemTime>,
    /// CLOCK_MONOTONIC when the read returned.
    pub read_at: Instant,
}

/// Counters of a [`BusSocket`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SocketStats {
    /// Data frames returned by [`BusSocket::recv`].
    pub frames_rx: u64,
    /// Error frames reported by the driver (bus-off, error passive, …), counted and dropped.
    pub error_frames: u64,
    /// Remote (RTR) frames, counted and dropped: this bus does not use them.
    pub remote_frames: u64,
    /// Frames written.
    pub frames_tx: u64,
}

/// A raw CAN socket bound to one interface.
#[derive(Debug)]
pub struct BusSocket {
    sock: CanSocket,
    iface: String,
    stats: SocketStats,
}

impl BusSocket {
    /// Opens `iface` non-blocking, with kernel receive timestamps and error frames enabled and a
    /// kernel filter that passes only standard data frames whose id is in `rx_ids`
    /// (an empty slice receives nothing; use [`BusSocket::open_all`] to receive everything).
    pub fn open(iface: &str, rx_ids: &[u32]) -> io::Result<Self> {
        let sock = CanSocket::open(iface).map_err(|e| {
            io::Error::new(e.kind(), format!("cannot open CAN interface {iface}: {e}"))
        })?;
        let filters: Vec<CanFilter> = rx_ids
            .iter()
            .map(|id| {
                CanFilter::new(
                    *id & CAN_SFF_MASK,
                    CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG,
                )
            })
            .collect();
        if filters.is_empty() {
            sock.set_filter_drop_all()?;
        } else {
            sock.set_filters(&filters)?;
        }
        Self::finish(sock, iface)
    }

    /// Opens `iface` receiving every frame (monitors, tests).
    pub fn open_all(iface: &str) -> io::Result<Self> {
        let sock = CanSocket::open(iface).map_err(|e| {
            io::Error::new(e.kind(), format!("cannot open CAN interface {iface}: {e}"))
        })?;
        sock.set_filter_accept_all()?;
        Self::finish(sock, iface)
    }

    fn finish(sock: CanSocket, iface: &str) -> io::Result<Self> {
        sock.set_error_filter_accept_all()?;
        sock.set_recv_timestamp(true)?;
        sock.set_nonblocking(true)?;
        Ok(Self {
            sock,
            iface: iface.to_owned(),
            stats: SocketStats::default(),
        })
    }

    /// Asks for a kernel receive queue of `bytes` (SO_RCVBUFFORCE where permitted, else
    /// SO_RCVBUF, which the kernel caps at `net.core.rmem_max`) and returns what the kernel
    /// granted (it counts its own overhead: a CAN frame costs several hundred bytes). A process
    /// that may be descheduled for a while under load (a logger, the actuator stubs) needs a
    /// deeper queue than the default ≈ 200 KiB, or frames queued meanwhile are dropped.
    pub fn set_receive_buffer(&self, bytes: usize) -> io::Result<usize> {
        use nix::sys::socket::{getsockopt, setsockopt, sockopt};
        use std::os::fd::AsFd;
        let fd = self.sock.as_fd();
        if setsockopt(&fd, sockopt::RcvBufForce, &bytes).is_err() {
            setsockopt(&fd, sockopt::RcvBuf, &bytes).map_err(io::Error::from)?;
        }
        getsockopt(&fd, sockopt::RcvBuf).map_err(io::Error::from)
    }

    /// The interface name.
    #[must_use]
    pub fn iface(&self) -> &str {
        &self.iface
    }

    /// Counters so far.
    #[must_use]
    pub fn stats(&self) -> &SocketStats {
        &self.stats
    }

    /// Next data frame, or `Ok(None)` if none is queued. Error and remote frames are counted and
    /// skipped. Never blocks.
    pub fn recv(&mut self) -> io::Result<Option<RxFrame>> {
        loop {
            let (frame, ts) = match self.sock.read_frame_with_timestamps() {
                Ok(x) => x,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            let read_at = Instant::now();
            match frame {
                CanFrame::Data(d) => {
                    self.stats.frames_rx = self.stats.frames_rx.saturating_add(1);
                    let id = if d.is_extended() {
                        d.raw_id() | CAN_EFF_FLAG
                    } else {
                        d.raw_id()
                    };
                    return Ok(Some(RxFrame {
                        frame: RawFrame::new(id, d.data()),
                        kernel_time: ts.socket,
                        read_at,
                    }));
                }
                CanFrame::Error(_) => {
                    self.stats.error_frames = self.stats.error_frames.saturating_add(1);
                }
                CanFrame::Remote(_) => {
                    self.stats.remote_frames = self.stats.remote_frames.saturating_add(1);
                }
            }
        }
    }

    /// Waits until the socket has something to read (a frame, an error frame) or `timeout_ms`
    /// passed, and says which. For a process with nothing to do between frames (the actuator
    /// stubs): it wakes when a frame arrives rather than polling on a short timer, which on an
    /// emulated bench costs thousands of wake-ups per second. A signal ends the wait early
    /// (`Ok(false)`), so a stop request is seen within one wait.
    pub fn wait_readable(&self, timeout_ms: u16) -> io::Result<bool> {
        use nix::poll::{poll, PollFd, PollFlags};
        use std::os::fd::AsFd;
        let mut fds = [PollFd::new(self.sock.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, timeout_ms) {
            Ok(n) => Ok(n > 0),
            Err(nix::errno::Errno::EINTR) => Ok(false),
            Err(e) => Err(io::Error::from(e)),
        }
    }

    /// Writes one frame. On a full transmit queue this returns `WouldBlock` (the caller decides
    /// whether to drop or retry next cycle; never blocks).
    pub fn send(&mut self, frame: &RawFrame) -> io::Result<()> {
        let id: socketcan::Id = if frame.id & CAN_EFF_FLAG != 0 {
            socketcan::ExtendedId::new(frame.id & !CAN_EFF_FLAG)
                .map(socketcan::Id::Extended)
                .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "bad extended id"))?
        } else {
            u16::try_from(frame.id)
                .ok()
                .and_then(socketcan::StandardId::new)
                .map(socketcan::Id::Standard)
                .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "bad standard id"))?
        };
        let data = CanDataFrame::new(id, frame.payload())
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "payload > 8 bytes"))?;
        self.sock.write_frame(&data)?;
        self.stats.frames_tx = self.stats.frames_tx.saturating_add(1);
        Ok(())
    }

    /// Writes an error frame, as a CAN controller reports one to the hosts on its interface
    /// (on vcan any sender can; receivers see it only with an error filter, as candump's
    /// `#FFFFFFFF`).
    pub fn send_error(&mut self, error: socketcan::CanError) -> io::Result<()> {
        let frame = socketcan::CanErrorFrame::from(error);
        self.sock.write_frame(&frame)?;
        self.stats.frames_tx = self.stats.frames_tx.saturating_add(1);
        Ok(())
    }

    /// Writes a generated message as it is (E2E fields untouched; use
    /// [`crate::E2eProtector::seal`] for protected frames).
    pub fn send_message<F: embedded_can::Frame>(&mut self, msg: &F) -> io::Result<()> {
        self.send(&RawFrame::from_message(msg))
    }

    /// The underlying socketcan socket, for options this wrapper does not cover.
    #[must_use]
    pub fn inner(&self) -> &CanSocket {
        &self.sock
    }
}

/// Whether `iface` exists and a raw CAN socket can be bound to it on this kernel.
#[must_use]
pub fn interface_usable(iface: &str) -> bool {
    CanSocket::open(iface).is_ok()
}
