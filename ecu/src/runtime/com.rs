//! The real com layer: iceoryx2 subscribers/publisher plus an optional CAN port.

use ipc::{
    AccelSubscriber, CrashAccelSample, DiagnosticsPublisher, EcuDiagnostics, IpcError, IpcNode,
    ObjectState, ObjectSubscriber, RxCounters, ServiceNames, TxCounters,
};

use super::activity::{CanFrame, CycleIo, IoError};

/// A non-blocking CAN port. **INTEGRATION POINT** for the `bus` crate's SocketCAN I/O
/// (kernel filters, non-blocking socket): implement this and pass it to
/// [`IceoryxIo::new`].
pub trait CanPort {
    /// Next received frame, or `None` when the socket has nothing queued (never blocks).
    fn try_recv(&mut self) -> Option<CanFrame>;
    /// Sends without blocking.
    fn try_send(&mut self, frame: &CanFrame) -> Result<(), IoError>;
}

/// Upper bound of CAN frames drained per cycle, so a flooded bus cannot starve the cycle.
const MAX_CAN_FRAMES_PER_CYCLE: usize = 64;

/// iceoryx2 inputs/outputs of the ECU process; polled every cycle, never waits.
pub struct IceoryxIo {
    objects: ObjectSubscriber,
    accel: AccelSubscriber,
    diagnostics: DiagnosticsPublisher,
    can: Option<Box<dyn CanPort>>,
    can_tx_errors: u64,
}

impl IceoryxIo {
    /// Opens (or creates) the three services on `node`. `can = None` switches CAN off.
    pub fn new(
        node: &IpcNode,
        names: &ServiceNames,
        can: Option<Box<dyn CanPort>>,
    ) -> Result<Self, IpcError> {
        Ok(Self {
            objects: ObjectSubscriber::new(node, names)?,
            accel: AccelSubscriber::new(node, names)?,
            diagnostics: DiagnosticsPublisher::new(node, names)?,
            can,
            can_tx_errors: 0,
        })
    }

    /// Object-state receive counters.
    pub fn object_counters(&self) -> RxCounters {
        self.objects.counters()
    }

    /// Accelerometer receive counters.
    pub fn accel_counters(&self) -> RxCounters {
        self.accel.counters()
    }

    /// Diagnostics send counters.
    pub fn diagnostics_counters(&self) -> TxCounters {
        self.diagnostics.counters()
    }

    /// CAN send failures (including sends while CAN is off).
    pub fn can_tx_errors(&self) -> u64 {
        self.can_tx_errors
    }
}

impl CycleIo for IceoryxIo {
    fn drain_objects(&mut self, f: &mut dyn FnMut(&ObjectState)) -> usize {
        self.objects.drain(f)
    }

    fn drain_accel(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize {
        self.accel.drain(f)
    }

    fn drain_can(&mut self, f: &mut dyn FnMut(&CanFrame)) -> usize {
        let Some(can) = self.can.as_mut() else {
            return 0;
        };
        let mut n = 0;
        while n < MAX_CAN_FRAMES_PER_CYCLE {
            match can.try_recv() {
                Some(frame) => {
                    f(&frame);
                    n += 1;
                }
                None => break,
            }
        }
        n
    }

    fn send_can(&mut self, frame: &CanFrame) -> Result<(), IoError> {
        let result = match self.can.as_mut() {
            Some(can) => can.try_send(frame),
            None => Err(IoError::CanDisabled),
        };
        if result.is_err() {
            self.can_tx_errors += 1;
        }
        result
    }

    fn publish_diagnostics(
        &mut self,
        fill: &mut dyn FnMut(&mut EcuDiagnostics),
    ) -> Result<(), IoError> {
        self.diagnostics
            .publish_with(EcuDiagnostics::ZERO, fill)
            .map_err(|_| IoError::Ipc)
    }

    fn can_enabled(&self) -> bool {
        self.can.is_some()
    }
}
