//! An in-memory com layer for simulated-clock tests of the cycle logic.

use std::collections::VecDeque;

use ipc::{CrashAccelSample, EcuDiagnostics, ObjectState};

use super::activity::{CanFrame, CycleIo, IoError};

/// Scripted inputs and captured outputs. Tests push inputs before a cycle and inspect
/// the outputs after it. (Allocates when queues grow; it is a test double.)
#[derive(Debug, Default)]
pub struct SimIo {
    /// Object states delivered on the next drain.
    pub objects: VecDeque<ObjectState>,
    /// Accelerometer batches delivered on the next drain.
    pub accel: VecDeque<CrashAccelSample>,
    /// CAN frames delivered on the next drain.
    pub can_rx: VecDeque<CanFrame>,
    /// Every CAN frame sent, in order.
    pub can_tx: Vec<CanFrame>,
    /// Every diagnostics record published, in order.
    pub diagnostics: Vec<EcuDiagnostics>,
    /// When false, CAN sends fail with [`IoError::CanDisabled`] and nothing is received.
    pub can_on: bool,
}

impl SimIo {
    /// An empty sim with CAN on.
    pub fn new() -> Self {
        Self {
            can_on: true,
            ..Self::default()
        }
    }
}

impl CycleIo for SimIo {
    fn drain_objects(&mut self, f: &mut dyn FnMut(&ObjectState)) -> usize {
        let n = self.objects.len();
        self.objects.drain(..).for_each(|o| f(&o));
        n
    }

    fn drain_accel(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize {
        let n = self.accel.len();
        self.accel.drain(..).for_each(|a| f(&a));
        n
    }

    fn drain_can(&mut self, f: &mut dyn FnMut(&CanFrame)) -> usize {
        if !self.can_on {
            self.can_rx.clear();
            return 0;
        }
        let n = self.can_rx.len();
        self.can_rx.drain(..).for_each(|c| f(&c));
        n
    }

    fn send_can(&mut self, frame: &CanFrame) -> Result<(), IoError> {
        if !self.can_on {
            return Err(IoError::CanDisabled);
        }
        self.can_tx.push(*frame);
        Ok(())
    }

    fn publish_diagnostics(
        &mut self,
        fill: &mut dyn FnMut(&mut EcuDiagnostics),
    ) -> Result<(), IoError> {
        let mut d = EcuDiagnostics::ZERO;
        fill(&mut d);
        self.diagnostics.push(d);
        Ok(())
    }

    fn can_enabled(&self) -> bool {
        self.can_on
    }
}
