//! The SocketCAN port of the ECU: [`CanPort`] over [`bus::socket::BusSocket`].
//!
//! Opened non-blocking with a kernel filter that passes only the ECU's input frames
//! ([`restraint::input_can_ids`]: EgoVehicleState, OccupantClassification, V2xOpponentMass), so the cycle
//! never spends time on other traffic and a flooded bus costs the kernel, not the cycle.
//! Nothing here allocates after [`SocketCanPort::open`].

use std::io;

use bus::socket::BusSocket;
use bus::RawFrame;

use crate::runtime::{CanPort, IoError};

/// A non-blocking, kernel-filtered SocketCAN port.
#[derive(Debug)]
pub struct SocketCanPort {
    sock: BusSocket,
    rx_errors: u64,
}

impl SocketCanPort {
    /// Opens `iface` receiving only `rx_ids` (standard ids).
    pub fn open(iface: &str, rx_ids: &[u32]) -> io::Result<Self> {
        Ok(Self {
            sock: BusSocket::open(iface, rx_ids)?,
            rx_errors: 0,
        })
    }

    /// Opens `iface` with the ECU's input filter.
    pub fn open_ecu(iface: &str) -> io::Result<Self> {
        Self::open(iface, &restraint::input_can_ids())
    }

    /// Socket counters (frames, error frames) and receive errors.
    pub fn stats(&self) -> (bus::socket::SocketStats, u64) {
        (*self.sock.stats(), self.rx_errors)
    }
}

impl CanPort for SocketCanPort {
    fn try_recv(&mut self) -> Option<RawFrame> {
        match self.sock.recv() {
            Ok(Some(rx)) => Some(rx.frame),
            Ok(None) => None,
            Err(_) => {
                self.rx_errors = self.rx_errors.saturating_add(1);
                None
            }
        }
    }

    fn try_send(&mut self, frame: &RawFrame) -> Result<(), IoError> {
        match self.sock.send(frame) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Err(IoError::CanWouldBlock),
            Err(_) => Err(IoError::CanIo),
        }
    }
}
