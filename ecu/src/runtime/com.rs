//! The real com layer: iceoryx2 subscribers (object list, crash accelerometer, safing
//! accelerometer, the two crush-zone satellites — each on its own service), the diagnostics
//! publisher and an optional CAN port.
//!
//! Inputs are polled on the cycle thread (iceoryx2 `receive()` does not allocate).
//! Diagnostics are *not* loaned on the cycle thread: iceoryx2 0.10's `loan_uninit`
//! heap-allocates a small reference-counted loan record on every call
//! (`ChunkMutSharedState::new` → `Rc::new`), which would put one malloc/free per cycle on
//! the real-time path. So the cycle writes the record in place into a preallocated,
//! wait-free triple buffer, and a normal-priority companion thread loans a shared-memory
//! chunk, writes the newest record into it and sends it. Monitors see the newest record
//! with at most one cycle period of extra delay; the cycle never allocates, locks or
//! blocks.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::Duration;

use ipc::{
    AccelSubscriber, CrashAccelSample, DiagnosticsPublisher, EcuDiagnostics, IpcError, IpcNode,
    ObjectState, ObjectSubscriber, RxCounters, SafingSubscriber, SatelliteFrames,
    SatelliteLeftSubscriber, SatelliteRightSubscriber, ServiceNames, TxCounters,
};
use triple_buffer::triple_buffer;

use bus::RawFrame;
use restraint::signals::SatelliteSide;
use restraint::{CycleIo, IoError, ReceiveErrors};

/// A non-blocking CAN port, implemented by [`crate::can_port::SocketCanPort`] over the bus
/// crate's SocketCAN socket (kernel filter, non-blocking) and passed to [`IceoryxIo::new`].
pub trait CanPort {
    /// Next received frame, or `None` when the socket has nothing queued (never blocks).
    fn try_recv(&mut self) -> Option<RawFrame>;
    /// Sends without blocking.
    fn try_send(&mut self, frame: &RawFrame) -> Result<(), IoError>;
}

/// Upper bound of CAN frames drained per cycle, so a flooded bus cannot starve the cycle.
const MAX_CAN_FRAMES_PER_CYCLE: usize = 64;

#[derive(Default)]
struct SharedTx {
    sent: AtomicU64,
    errors: AtomicU64,
}

/// The companion thread that publishes diagnostics records handed over by the cycle.
struct DiagnosticsOffload {
    stop: Arc<AtomicBool>,
    counters: Arc<SharedTx>,
    thread: Option<JoinHandle<()>>,
}

impl DiagnosticsOffload {
    fn spawn(
        node_name: String,
        names: ServiceNames,
        poll: Duration,
        mut out: triple_buffer::Output<EcuDiagnostics>,
    ) -> Result<Self, IpcError> {
        let stop = Arc::new(AtomicBool::new(false));
        let counters = Arc::new(SharedTx::default());
        let (ready_tx, ready_rx) = mpsc::channel::<Result<(), IpcError>>();
        let (stop_t, counters_t) = (stop.clone(), counters.clone());
        let thread = std::thread::Builder::new()
            .name("ecu-diag-pub".into())
            .spawn(move || {
                // iceoryx2 ipc ports are not `Send`: node and publisher live in this thread.
                let setup = ipc::create_node(&node_name, false).and_then(|(node, _)| {
                    DiagnosticsPublisher::new(&node, &names).map(|p| (node, p))
                });
                let (_node, mut publisher) = match setup {
                    Ok(v) => {
                        let _ = ready_tx.send(Ok(()));
                        v
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return;
                    }
                };
                let mut publish_newest = |out: &mut triple_buffer::Output<EcuDiagnostics>| {
                    if out.update() {
                        let c = match publisher.publish(*out.output_buffer()) {
                            Ok(()) => &counters_t.sent,
                            Err(_) => &counters_t.errors,
                        };
                        c.fetch_add(1, Ordering::Relaxed);
                    }
                };
                while !stop_t.load(Ordering::Relaxed) {
                    publish_newest(&mut out);
                    std::thread::sleep(poll);
                }
                publish_newest(&mut out); // flush the final record
            })
            .map_err(|e| IpcError::Setup {
                what: "diagnostics thread spawn",
                name: names_for_error(),
                detail: e.to_string(),
            })?;
        let ready = ready_rx.recv().unwrap_or_else(|_| {
            Err(IpcError::Setup {
                what: "diagnostics thread start",
                name: names_for_error(),
                detail: "thread ended before reporting".into(),
            })
        });
        let mut me = Self {
            stop,
            counters,
            thread: Some(thread),
        };
        match ready {
            Ok(()) => Ok(me),
            Err(e) => {
                me.finish();
                Err(e)
            }
        }
    }

    fn finish(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn names_for_error() -> String {
    ipc::DIAGNOSTICS_SUFFIX.to_owned()
}

impl Drop for DiagnosticsOffload {
    fn drop(&mut self) {
        self.finish();
    }
}

/// iceoryx2 inputs/outputs of the ECU process; polled every cycle, never waits.
pub struct IceoryxIo {
    objects: ObjectSubscriber,
    accel: AccelSubscriber,
    /// The safing accelerometer: an independent sensor on its own service (never merged with
    /// the crash accelerometer's).
    safing: SafingSubscriber,
    /// The crush-zone satellites, each on its own service.
    satellite_left: SatelliteLeftSubscriber,
    satellite_right: SatelliteRightSubscriber,
    diagnostics: triple_buffer::Input<EcuDiagnostics>,
    offload: DiagnosticsOffload,
    diagnostics_written: u64,
    can: Option<Box<dyn CanPort>>,
    can_tx_errors: u64,
}

impl IceoryxIo {
    /// Opens (or creates) the input services on `node` and starts the diagnostics
    /// companion thread (own node `{node name}-diag`, polling every `diag_poll`).
    /// `can = None` switches CAN off.
    pub fn new(
        node: &IpcNode,
        names: &ServiceNames,
        can: Option<Box<dyn CanPort>>,
        diag_poll: Duration,
    ) -> Result<Self, IpcError> {
        let objects = ObjectSubscriber::new(node, names)?;
        let accel = AccelSubscriber::new(node, names)?;
        let safing = SafingSubscriber::new(node, names)?;
        let satellite_left = SatelliteLeftSubscriber::new(node, names)?;
        let satellite_right = SatelliteRightSubscriber::new(node, names)?;
        let (input, output) = triple_buffer(&EcuDiagnostics::ZERO);
        let offload = DiagnosticsOffload::spawn(
            format!("{}-diag", node.name().as_str()),
            names.clone(),
            diag_poll,
            output,
        )?;
        Ok(Self {
            objects,
            accel,
            safing,
            satellite_left,
            satellite_right,
            diagnostics: input,
            offload,
            diagnostics_written: 0,
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

    /// Safing accelerometer receive counters.
    pub fn safing_counters(&self) -> RxCounters {
        self.safing.counters()
    }

    /// The left and the right satellite's receive counters.
    pub fn satellite_counters(&self) -> [RxCounters; 2] {
        [
            self.satellite_left.counters(),
            self.satellite_right.counters(),
        ]
    }

    /// Records written by the cycle (every call of `publish_diagnostics`).
    pub fn diagnostics_written(&self) -> u64 {
        self.diagnostics_written
    }

    /// Diagnostics actually sent over iceoryx2 by the companion thread (newest-wins:
    /// records overwritten before the thread ran are not sent).
    pub fn diagnostics_counters(&self) -> TxCounters {
        TxCounters {
            sent: self.offload.counters.sent.load(Ordering::Relaxed),
            errors: self.offload.counters.errors.load(Ordering::Relaxed),
        }
    }

    /// Stops the diagnostics thread after it has sent the last record.
    pub fn shutdown(&mut self) {
        self.offload.finish();
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

    fn drain_safing(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize {
        // The same poll-only drain as the crash accelerometer's: no allocation, no lock, no
        // wait; a receive error ends the drain and is counted (`receive_errors().safing`).
        self.safing.drain(f)
    }

    fn drain_satellites(&mut self, f: &mut dyn FnMut(SatelliteSide, &SatelliteFrames)) -> usize {
        // Poll-only as the accelerometers'; a receive error ends that satellite's drain and is
        // counted in its port's counters (a missing satellite only takes its relief away).
        self.satellite_left
            .drain(|b: &SatelliteFrames| f(SatelliteSide::Left, b))
            + self
                .satellite_right
                .drain(|b: &SatelliteFrames| f(SatelliteSide::Right, b))
    }

    fn drain_can(&mut self, f: &mut dyn FnMut(&RawFrame)) -> usize {
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

    fn send_can(&mut self, frame: &RawFrame) -> Result<(), IoError> {
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
        // The back buffer holds a record from two writes ago: reset, fill, publish.
        let buf = self.diagnostics.input_buffer_mut();
        *buf = EcuDiagnostics::ZERO;
        fill(buf);
        self.diagnostics.publish();
        self.diagnostics_written += 1;
        Ok(())
    }

    fn can_enabled(&self) -> bool {
        self.can.is_some()
    }

    fn receive_errors(&self) -> ReceiveErrors {
        ReceiveErrors {
            objects: self.objects.counters().errors,
            accel: self.accel.counters().errors,
            safing: self.safing.counters().errors,
        }
    }
}
