//! A trivial test activity of the shell's tests: drains the inputs and publishes diagnostics
//! every cycle, takes no restraint decisions (mode stays `Monitoring`). It lets the shell's
//! loop, iceoryx2 I/O and allocation tests run without the restraint logic in the way.
#![allow(dead_code)]

use restraint::{Activity, CycleInfo, CycleIo, Degraded, EcuMode, StartupError};

/// Object state older than this (by receipt time) counts as stale.
const OBJECT_STALE_AFTER_NS: u64 = 100_000_000;

/// Drains inputs, counts them and publishes a diagnostics record per cycle.
#[derive(Debug, Default, Clone)]
pub struct PassthroughActivity {
    objects_rx: u64,
    accel_batches_rx: u64,
    accel_samples_rx: u64,
    can_frames_rx: u64,
    last_object_sequence: u64,
    last_accel_sequence: u64,
    last_object_rx_ns: Option<u64>,
    object_stale_cycles: u64,
    non_finite_inputs: u64,
    diagnostics_failures: u64,
}

impl PassthroughActivity {
    /// A fresh activity.
    pub fn new() -> Self {
        Self::default()
    }

    /// Object states received so far.
    pub fn objects_rx(&self) -> u64 {
        self.objects_rx
    }

    /// Accelerometer batches received so far.
    pub fn accel_batches_rx(&self) -> u64 {
        self.accel_batches_rx
    }
}

impl Activity for PassthroughActivity {
    fn name(&self) -> &'static str {
        "passthrough"
    }

    fn startup(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) -> Result<(), StartupError> {
        Ok(())
    }

    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        let mut last_obj = self.last_object_sequence;
        let mut non_finite = 0u64;
        let n_obj = io.drain_objects(&mut |o| {
            last_obj = o.sequence;
            if !(o.distance_m.is_finite() && o.closing_speed_mps.is_finite()) {
                non_finite += 1;
            }
        });
        let mut last_acc = self.last_accel_sequence;
        let mut samples = 0u64;
        let n_acc = io.drain_accel(&mut |a| {
            last_acc = a.sequence;
            samples += a.samples().len() as u64;
            non_finite += a.samples().iter().filter(|v| !v.is_finite()).count() as u64;
        });
        let n_can = io.drain_can(&mut |_| {});

        self.objects_rx += n_obj as u64;
        self.accel_batches_rx += n_acc as u64;
        self.accel_samples_rx += samples;
        self.can_frames_rx += n_can as u64;
        self.non_finite_inputs += non_finite;
        self.last_object_sequence = last_obj;
        self.last_accel_sequence = last_acc;
        if n_obj > 0 {
            self.last_object_rx_ns = Some(info.now_ns);
        }
        let object_stale = self
            .last_object_rx_ns
            .is_none_or(|t| info.now_ns.saturating_sub(t) > OBJECT_STALE_AFTER_NS);
        self.object_stale_cycles += u64::from(object_stale);

        let mut reasons = Degraded::empty();
        reasons.set(Degraded::OBJECT_STALE, object_stale);
        reasons.set(Degraded::CAN_DISABLED, !io.can_enabled());
        let (objects_rx, accel_rx) = (self.objects_rx, self.accel_batches_rx);
        let published = io.publish_diagnostics(&mut |d| {
            *d = restraint::EcuDiagnostics::ZERO; // writes only some fields
            d.timestamp_ns = info.now_ns;
            d.cycle_count = info.cycle + 1;
            d.overrun_count = info.overruns;
            d.last_exec_ns = info.last_exec_ns;
            d.wake_latency_ns = info.wake_latency_ns;
            d.last_object_sequence = last_obj;
            d.last_accel_sequence = last_acc;
            d.object_samples_rx = objects_rx;
            d.accel_batches_rx = accel_rx;
            d.mode = EcuMode::Monitoring as u8;
            d.degraded_reasons = reasons.bits();
        });
        if published.is_err() {
            self.diagnostics_failures += 1;
        }
    }

    fn shutdown(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) {}

    fn report_counters(&self, out: &mut dyn FnMut(&'static str, u64)) {
        for (name, v) in [
            ("objects_rx", self.objects_rx),
            ("accel_batches_rx", self.accel_batches_rx),
            ("accel_samples_rx", self.accel_samples_rx),
            ("can_frames_rx", self.can_frames_rx),
            ("object_stale_cycles", self.object_stale_cycles),
            ("non_finite_inputs", self.non_finite_inputs),
            ("diagnostics_publish_failures", self.diagnostics_failures),
        ] {
            out(name, v);
        }
    }
}

/// The shell's own check of its test activity (runs with every test binary that uses it).
#[test]
fn passthrough_drains_counts_and_flags_staleness() {
    use restraint::{CrashAccelSample, ObjectState, SimIo};
    let mut io = SimIo::new();
    io.can_on = false;
    let mut a = PassthroughActivity::new();
    let mut o = ObjectState::INVALID;
    o.sequence = 7;
    o.distance_m = f32::NAN;
    io.push_object(o);
    let mut acc = CrashAccelSample::EMPTY;
    acc.sequence = 3;
    acc.count = 99; // corrupt: clamped to capacity
    io.push_accel(acc);
    let mut info = CycleInfo {
        now_ns: 1_000_000,
        ..CycleInfo::default()
    };
    a.step(&info, &mut io);
    let d0 = io.diagnostics;
    info.cycle = 1;
    info.now_ns += 200_000_000; // 200 ms later, nothing new → stale
    a.step(&info, &mut io);

    assert_eq!(io.diagnostics_published, 2);
    assert_eq!((d0.last_object_sequence, d0.last_accel_sequence), (7, 3));
    assert_eq!(d0.degraded_reasons, Degraded::CAN_DISABLED.bits());
    let d1 = io.diagnostics;
    assert_eq!(d1.cycle_count, 2);
    assert_eq!(
        d1.degraded(),
        Degraded::CAN_DISABLED | Degraded::OBJECT_STALE
    );
    let mut c = Vec::new();
    a.report_counters(&mut |n, v| c.push((n, v)));
    assert!(c.contains(&("accel_samples_rx", 8)));
    assert!(c.contains(&("non_finite_inputs", 1)));
    assert!(c.contains(&("object_stale_cycles", 1)));
}
