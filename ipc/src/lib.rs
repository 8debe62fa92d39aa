//! iceoryx2 zero-copy payload types and service names shared by the bench processes.
//!
//! Every process of the bench (ECU, sensor feeds, monitors, tests) talks over the
//! services defined here. Keeping the payload layouts, the service names and **all**
//! port settings in this one crate is what makes `open_or_create` succeed from any
//! side: iceoryx2 refuses to open a service whose static settings are incompatible
//! with the ones requested, so every opener must request the same ones.
//!
//! Payloads are `#[repr(C)]`, `Copy`, fixed-size and pointer-free so they can live in
//! shared memory and be read in place (zero-copy). Flags are `u8`, not `bool`: a
//! publisher in another process could write any byte, and a `bool` other than 0/1 is
//! undefined behaviour in Rust, whereas a `u8` is always valid.
//!
//! The subscriber wrappers are poll-only (`receive()` every cycle, no event waits) and
//! their hot-path methods neither allocate nor block; errors on the hot path are
//! counted, not formatted.

use core::fmt;

use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

pub use iceoryx2;

mod stop;
pub use stop::install_stop_signals;

/// The iceoryx2 service flavour used by the bench: inter-process shared memory.
pub type IpcService = iceoryx2::service::ipc::Service;
/// A node of the bench's iceoryx2 flavour.
pub type IpcNode = Node<IpcService>;

// ---------------------------------------------------------------------------------------
// Service names and port settings: the ONE place.
// ---------------------------------------------------------------------------------------

/// Default prefix of every service name. Tests pass a unique prefix so that parallel
/// test runs on one machine never see each other's samples.
pub const DEFAULT_SERVICE_PREFIX: &str = "restraint-bench";

/// Suffix of the opponent-object / pre-crash state service (sensor feeds → ECU).
pub const OBJECT_STATE_SUFFIX: &str = "ecu/in/object_state";
/// Suffix of the compartment crash-accelerometer service (sensor feeds → ECU).
pub const CRASH_ACCEL_SUFFIX: &str = "ecu/in/crash_accel";
/// Suffix of the ECU diagnostics service (ECU → monitors).
pub const DIAGNOSTICS_SUFFIX: &str = "ecu/out/diagnostics";
/// Suffix of the bench-truth service (sensor feeds → actuator stubs; never read by the ECU).
pub const BENCH_TRUTH_SUFFIX: &str = "bench/truth";

/// Static settings of one publish-subscribe service. Every opener uses exactly these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PortSettings {
    /// Samples a subscriber queue holds before the oldest is overwritten (safe overflow).
    pub subscriber_buffer: usize,
    /// Samples a late-joining subscriber receives on connect.
    pub history: usize,
    /// Publishers allowed on the service (e.g. a feed and a replay tool).
    pub max_publishers: usize,
    /// Subscribers allowed on the service (ECU, monitors, loggers, tests).
    pub max_subscribers: usize,
    /// Nodes allowed to open the service.
    pub max_nodes: usize,
    /// Samples a subscriber may hold at once; the ECU holds one at a time.
    pub max_borrowed: usize,
}

/// Object state arrives every ~10–20 ms; the ECU only needs the newest, a small queue
/// absorbs a stalled cycle without losing the latest value (safe overflow drops oldest).
pub const OBJECT_STATE_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 8,
    history: 1,
    max_publishers: 2,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Accelerometer batches arrive at ≥ 1 kHz of batches of up to
/// [`ACCEL_BATCH_CAPACITY`] samples; every sample matters for crash confirmation, so
/// the queue covers ~64 ms of a stalled ECU at 1 kHz batches.
pub const CRASH_ACCEL_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 64,
    history: 0,
    max_publishers: 2,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Diagnostics are published every ECU cycle; monitors only show the newest.
pub const DIAGNOSTICS_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 16,
    history: 1,
    max_publishers: 1,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Bench truth is published every ~10 ms and at the end; the stubs need only the newest
/// (history 1 so a late-starting stub still learns the start time).
pub const BENCH_TRUTH_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 8,
    history: 1,
    max_publishers: 1,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Fully qualified service names for one prefix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    /// Opponent-object state service.
    pub object_state: String,
    /// Crash accelerometer service.
    pub crash_accel: String,
    /// ECU diagnostics service.
    pub diagnostics: String,
    /// Bench-truth service (sensor feeds → actuator stubs).
    pub bench_truth: String,
}

impl ServiceNames {
    /// Names under `prefix` (no trailing slash), e.g. `restraint-bench/ecu/in/object_state`.
    pub fn with_prefix(prefix: &str) -> Self {
        let p = prefix.trim_end_matches('/');
        Self {
            object_state: format!("{p}/{OBJECT_STATE_SUFFIX}"),
            crash_accel: format!("{p}/{CRASH_ACCEL_SUFFIX}"),
            diagnostics: format!("{p}/{DIAGNOSTICS_SUFFIX}"),
            bench_truth: format!("{p}/{BENCH_TRUTH_SUFFIX}"),
        }
    }
}

impl Default for ServiceNames {
    fn default() -> Self {
        Self::with_prefix(DEFAULT_SERVICE_PREFIX)
    }
}

// ---------------------------------------------------------------------------------------
// Payload types
// ---------------------------------------------------------------------------------------

/// `valid` flag value meaning "the producer vouches for this object".
pub const VALID: u8 = 1;

/// Opponent object / pre-crash state from the environment sensors (one tracked object).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
pub struct ObjectState {
    /// CLOCK_MONOTONIC time of the measurement (not of publication), ns.
    pub timestamp_ns: u64,
    /// Publisher sequence counter; gaps reveal dropped samples.
    pub sequence: u64,
    /// Longitudinal distance to the object, m (positive ahead).
    pub distance_m: f32,
    /// Closing speed, m/s (positive = approaching).
    pub closing_speed_mps: f32,
    /// Relative acceleration (rate of change of closing speed), m/s².
    pub relative_accel_mps2: f32,
    /// Estimated opponent mass, kg.
    pub opponent_mass_kg: f32,
    /// One-sigma uncertainty of the opponent mass, kg.
    pub opponent_mass_sigma_kg: f32,
    /// Track confidence 0..1.
    pub confidence: f32,
    /// Tracker object id.
    pub object_id: u32,
    /// [`VALID`] (1) if the track is valid; anything else is invalid.
    pub valid: u8,
    /// Explicit padding so the layout has no implicit holes.
    pub _reserved: [u8; 3],
}

impl ObjectState {
    /// An invalid, all-zero state (used as the "nothing received" value).
    pub const INVALID: Self = Self {
        timestamp_ns: 0,
        sequence: 0,
        distance_m: 0.0,
        closing_speed_mps: 0.0,
        relative_accel_mps2: 0.0,
        opponent_mass_kg: 0.0,
        opponent_mass_sigma_kg: 0.0,
        confidence: 0.0,
        object_id: 0,
        valid: 0,
        _reserved: [0; 3],
    };

    /// True if the producer flagged the track valid (does not check the values).
    pub fn is_valid(&self) -> bool {
        self.valid == VALID
    }
}

impl Default for ObjectState {
    fn default() -> Self {
        Self::INVALID
    }
}

/// Maximum samples in one [`CrashAccelSample`] batch.
pub const ACCEL_BATCH_CAPACITY: usize = 8;

/// A small batch of compartment accelerometer samples (longitudinal, vehicle frame).
///
/// Batching keeps the sample rate (e.g. 4–8 kHz) decoupled from the IPC message rate.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
pub struct CrashAccelSample {
    /// CLOCK_MONOTONIC time of `accel_mps2[0]`, ns.
    pub first_timestamp_ns: u64,
    /// Publisher sequence counter.
    pub sequence: u64,
    /// Time between consecutive samples, ns.
    pub sample_period_ns: u32,
    /// Number of valid entries in `accel_mps2` (values above capacity are clamped by readers).
    pub count: u32,
    /// Longitudinal acceleration, m/s² (negative = deceleration).
    pub accel_mps2: [f32; ACCEL_BATCH_CAPACITY],
}

impl CrashAccelSample {
    /// An empty batch.
    pub const EMPTY: Self = Self {
        first_timestamp_ns: 0,
        sequence: 0,
        sample_period_ns: 0,
        count: 0,
        accel_mps2: [0.0; ACCEL_BATCH_CAPACITY],
    };

    /// The valid samples; a corrupt `count` is clamped, so this never panics.
    pub fn samples(&self) -> &[f32] {
        let n = (self.count as usize).min(ACCEL_BATCH_CAPACITY);
        self.accel_mps2.get(..n).unwrap_or(&[])
    }
}

impl Default for CrashAccelSample {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Points of the predicted pulse carried in [`EcuDiagnostics`].
pub const PULSE_POINTS: usize = 64;

/// ECU operating mode as carried in diagnostics (`EcuDiagnostics::mode`).
#[repr(u8)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EcuMode {
    /// Runtime up, cycle logic not yet running.
    Startup = 0,
    /// Normal monitoring.
    Monitoring = 1,
    /// Collision predicted, settings preset.
    PreCrash = 2,
    /// Crash confirmed by the accelerometer.
    Crash = 3,
    /// After the crash.
    PostCrash = 4,
    /// Inputs degraded: conventional reference restraint.
    Degraded = 5,
}

impl EcuMode {
    /// Decodes a raw mode byte; unknown values map to `None`.
    pub fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::Startup,
            1 => Self::Monitoring,
            2 => Self::PreCrash,
            3 => Self::Crash,
            4 => Self::PostCrash,
            5 => Self::Degraded,
            _ => return None,
        })
    }

    /// Short display name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Startup => "startup",
            Self::Monitoring => "monitoring",
            Self::PreCrash => "pre-crash",
            Self::Crash => "crash",
            Self::PostCrash => "post-crash",
            Self::Degraded => "degraded",
        }
    }
}

/// Degraded-reason bits (`EcuDiagnostics::degraded_reasons`).
pub mod degraded {
    /// Object state missing or older than the staleness limit.
    pub const OBJECT_STALE: u32 = 1 << 0;
    /// Object state present but invalid / out of range / NaN.
    pub const OBJECT_INVALID: u32 = 1 << 1;
    /// Accelerometer samples missing or stale.
    pub const ACCEL_STALE: u32 = 1 << 2;
    /// Accelerometer samples invalid.
    pub const ACCEL_INVALID: u32 = 1 << 3;
    /// CAN inputs stale (vehicle speed, occupant).
    pub const CAN_STALE: u32 = 1 << 4;
    /// E2E check failed on a CAN input.
    pub const E2E_FAILURE: u32 = 1 << 5;
    /// Characteristic diagram (LUT) missing or invalid.
    pub const LUT_INVALID: u32 = 1 << 6;
    /// CAN side switched off (`--no-can`) or unavailable.
    pub const CAN_DISABLED: u32 = 1 << 7;
    /// IPC receive errors this cycle.
    pub const IPC_ERROR: u32 = 1 << 8;
}

/// ECU diagnostics, published every cycle (predicted pulse, chosen settings, mode, timing).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
pub struct EcuDiagnostics {
    /// CLOCK_MONOTONIC time of the cycle that produced this record, ns.
    pub timestamp_ns: u64,
    /// Cycles run since start.
    pub cycle_count: u64,
    /// Cycles that ended after the next deadline (skipped slots are not re-run).
    pub overrun_count: u64,
    /// Execution time of the previous cycle, ns.
    pub last_exec_ns: u64,
    /// Wake-up latency of this cycle (actual wake − deadline), ns.
    pub wake_latency_ns: u64,
    /// Sequence of the newest object state seen (0 = none).
    pub last_object_sequence: u64,
    /// Sequence of the newest accelerometer batch seen (0 = none).
    pub last_accel_sequence: u64,
    /// Object states received since start.
    pub object_samples_rx: u64,
    /// Accelerometer batches received since start.
    pub accel_batches_rx: u64,
    /// Predicted velocity change of the ego vehicle, m/s.
    pub predicted_delta_v_mps: f32,
    /// Predicted peak deceleration magnitude, m/s².
    pub predicted_a_max_mps2: f32,
    /// Predicted mean deceleration magnitude, m/s².
    pub predicted_a_mean_mps2: f32,
    /// Predicted contact duration, s.
    pub predicted_contact_time_s: f32,
    /// Predicted time to contact, s (negative/NaN when none).
    pub time_to_contact_s: f32,
    /// Time between consecutive `pulse_accel_mps2` points, s.
    pub pulse_dt_s: f32,
    /// Predicted pulse, ego acceleration m/s², from contact on.
    pub pulse_accel_mps2: [f32; PULSE_POINTS],
    /// Number of valid pulse points.
    pub pulse_points: u32,
    /// Chosen belt load-limiter level, N.
    pub belt_force_limit_n: f32,
    /// Chosen pretensioner fire time relative to predicted contact, s.
    pub pretensioner_time_s: f32,
    /// Chosen airbag fire time relative to contact, s.
    pub airbag_time_s: f32,
    /// Chosen airbag stage/level (0 = no fire).
    pub airbag_stage: u8,
    /// [`EcuMode`] as a byte.
    pub mode: u8,
    /// 1 if the pretensioner is commanded/fired.
    pub pretensioner_fired: u8,
    /// 1 if the airbag is commanded/fired.
    pub airbag_fired: u8,
    /// Bitset of [`degraded`] reasons.
    pub degraded_reasons: u32,
}

impl EcuDiagnostics {
    /// All-zero record in [`EcuMode::Startup`].
    pub const ZERO: Self = Self {
        timestamp_ns: 0,
        cycle_count: 0,
        overrun_count: 0,
        last_exec_ns: 0,
        wake_latency_ns: 0,
        last_object_sequence: 0,
        last_accel_sequence: 0,
        object_samples_rx: 0,
        accel_batches_rx: 0,
        predicted_delta_v_mps: 0.0,
        predicted_a_max_mps2: 0.0,
        predicted_a_mean_mps2: 0.0,
        predicted_contact_time_s: 0.0,
        time_to_contact_s: f32::NAN,
        pulse_dt_s: 0.0,
        pulse_accel_mps2: [0.0; PULSE_POINTS],
        pulse_points: 0,
        belt_force_limit_n: 0.0,
        pretensioner_time_s: 0.0,
        airbag_time_s: 0.0,
        airbag_stage: 0,
        mode: EcuMode::Startup as u8,
        pretensioner_fired: 0,
        airbag_fired: 0,
        degraded_reasons: 0,
    };
}

impl Default for EcuDiagnostics {
    fn default() -> Self {
        Self::ZERO
    }
}

/// Capacity of [`BenchTruth::scenario_name`] (UTF-8 bytes, zero padded).
pub const SCENARIO_NAME_CAPACITY: usize = 64;

/// What really happened in the played scenario (sensor feeds → actuator stubs, tests).
///
/// The ECU never subscribes to this: it is the bench's ground truth, used to judge the
/// ECU's commands against the true contact instant and the true crash.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
pub struct BenchTruth {
    /// CLOCK_MONOTONIC time of publication, ns.
    pub timestamp_ns: u64,
    /// Publisher sequence counter.
    pub sequence: u64,
    /// CLOCK_MONOTONIC time of scenario t = 0, ns.
    pub start_ns: u64,
    /// CLOCK_MONOTONIC time of the true first contact, ns; 0 = no contact (yet, or avoided).
    pub contact_ns: u64,
    /// True ego mass, kg.
    pub ego_mass_kg: f32,
    /// True opponent mass, kg (`f32::INFINITY` = rigid barrier).
    pub opponent_mass_kg: f32,
    /// True closing speed at contact, m/s (0 until contact).
    pub closing_speed_at_contact_mps: f32,
    /// Number of valid bytes in `scenario_name`.
    pub scenario_name_len: u32,
    /// Scenario name, UTF-8, zero padded.
    pub scenario_name: [u8; SCENARIO_NAME_CAPACITY],
    /// 1 when the scenario has finished playing (no more feeds will follow).
    pub done: u8,
    /// Explicit padding so the layout has no implicit holes.
    pub _reserved: [u8; 7],
}

impl BenchTruth {
    /// Nothing known yet.
    pub const EMPTY: Self = Self {
        timestamp_ns: 0,
        sequence: 0,
        start_ns: 0,
        contact_ns: 0,
        ego_mass_kg: 0.0,
        opponent_mass_kg: 0.0,
        closing_speed_at_contact_mps: 0.0,
        scenario_name_len: 0,
        scenario_name: [0; SCENARIO_NAME_CAPACITY],
        done: 0,
        _reserved: [0; 7],
    };

    /// Stores `name`, truncated at a character boundary to the capacity.
    pub fn set_scenario_name(&mut self, name: &str) {
        let mut end = name.len().min(SCENARIO_NAME_CAPACITY);
        while !name.is_char_boundary(end) {
            end -= 1;
        }
        self.scenario_name = [0; SCENARIO_NAME_CAPACITY];
        self.scenario_name[..end].copy_from_slice(&name.as_bytes()[..end]);
        self.scenario_name_len = end as u32;
    }

    /// The scenario name (invalid UTF-8 or a corrupt length yields the valid prefix).
    pub fn scenario_name(&self) -> &str {
        let n = (self.scenario_name_len as usize).min(SCENARIO_NAME_CAPACITY);
        let bytes = self.scenario_name.get(..n).unwrap_or(&[]);
        let text = match core::str::from_utf8(bytes) {
            Ok(s) => s,
            Err(e) => core::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or(""),
        };
        text.trim_end_matches('\0')
    }

    /// True once the feeds have finished.
    pub fn is_done(&self) -> bool {
        self.done == 1
    }
}

impl Default for BenchTruth {
    fn default() -> Self {
        Self::EMPTY
    }
}

// ---------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------

/// Set-up errors (node, service or port creation). Only produced at start-up, so they
/// may carry formatted text.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// The service name is not a valid iceoryx2 service name.
    #[error("invalid iceoryx2 service name {name:?}: {detail}")]
    ServiceName {
        /// The offending name.
        name: String,
        /// iceoryx2's reason.
        detail: String,
    },
    /// An iceoryx2 set-up call failed.
    #[error("iceoryx2 {what} failed for {name:?}: {detail}")]
    Setup {
        /// What was being created.
        what: &'static str,
        /// Service or node name.
        name: String,
        /// iceoryx2's reason.
        detail: String,
    },
}

fn setup_err(what: &'static str, name: &str, e: impl fmt::Debug) -> IpcError {
    IpcError::Setup {
        what,
        name: name.to_owned(),
        detail: format!("{e:?}"),
    }
}

// ---------------------------------------------------------------------------------------
// Node
// ---------------------------------------------------------------------------------------

/// Result of the start-up cleanup of resources left by killed processes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StaleCleanup {
    /// Dead nodes whose resources were removed.
    pub cleaned: u64,
    /// Dead nodes that could not be removed (permissions, concurrently being cleaned).
    pub failed: u64,
}

/// Creates a node named `name` and removes resources of dead nodes first.
///
/// `handle_signals = false` keeps iceoryx2 from installing its own SIGINT/SIGTERM
/// handlers, so the ECU's handler (which only sets a flag) stays in charge.
/// A killed process (SIGKILL, crash) leaves its node and port records in shared memory;
/// `try_cleanup_dead_nodes` removes them so a restarted bench does not hit
/// "service in use / too many publishers" errors. With iceoryx2 0.10's default config
/// (`cleanup_dead_nodes_on_creation = true`) node creation already did this, so the
/// explicit call usually reports 0; it still catches nodes that died in between and
/// configs that turn the automatic cleanup off. (Verified: ECU SIGKILLed and restarted
/// with the same names — the dead nodes are detected and removed at creation.)
pub fn create_node(name: &str, handle_signals: bool) -> Result<(IpcNode, StaleCleanup), IpcError> {
    // iceoryx2 warns on every start that no config file exists (defaults are what the
    // bench wants); keep warnings quiet unless IOX2_LOG_LEVEL asks for them.
    set_log_level_from_env_or(LogLevel::Error);
    let node_name = NodeName::new(name).map_err(|e| setup_err("node name", name, e))?;
    let mode = if handle_signals {
        SignalHandlingMode::HandleTerminationRequests
    } else {
        SignalHandlingMode::Disabled
    };
    let node = NodeBuilder::new()
        .name(&node_name)
        .signal_handling_mode(mode)
        .create::<IpcService>()
        .map_err(|e| setup_err("node creation", name, e))?;
    let state = node.try_cleanup_dead_nodes();
    Ok((
        node,
        StaleCleanup {
            cleaned: state.cleanups,
            failed: state.failed_cleanups,
        },
    ))
}

fn open_service<T: fmt::Debug + ZeroCopySend + 'static>(
    node: &IpcNode,
    name: &str,
    ports: &PortSettings,
) -> Result<PubSubFactory<IpcService, T, ()>, IpcError> {
    let service_name = ServiceName::new(name).map_err(|e| IpcError::ServiceName {
        name: name.to_owned(),
        detail: format!("{e:?}"),
    })?;
    node.service_builder(&service_name)
        .publish_subscribe::<T>()
        .enable_safe_overflow(true)
        .subscriber_max_buffer_size(ports.subscriber_buffer)
        .history_size(ports.history)
        .max_publishers(ports.max_publishers)
        .max_subscribers(ports.max_subscribers)
        .max_nodes(ports.max_nodes)
        .subscriber_max_borrowed_samples(ports.max_borrowed)
        .open_or_create()
        .map_err(|e| setup_err("service open_or_create", name, e))
}

// ---------------------------------------------------------------------------------------
// Typed wrappers
// ---------------------------------------------------------------------------------------

/// Counters of a polled subscriber (hot path: counts only, never formats).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RxCounters {
    /// Samples received since creation.
    pub received: u64,
    /// `receive()` calls that returned an error.
    pub errors: u64,
}

/// A poll-only typed subscriber.
pub struct PolledSubscriber<T: fmt::Debug + ZeroCopySend + Copy + 'static> {
    _service: PubSubFactory<IpcService, T, ()>,
    subscriber: Subscriber<IpcService, T, ()>,
    counters: RxCounters,
    latest: Option<T>,
}

impl<T: fmt::Debug + ZeroCopySend + Copy + 'static> PolledSubscriber<T> {
    fn create(node: &IpcNode, name: &str, ports: &PortSettings) -> Result<Self, IpcError> {
        let service = open_service::<T>(node, name, ports)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(ports.subscriber_buffer)
            .create()
            .map_err(|e| setup_err("subscriber creation", name, e))?;
        Ok(Self {
            _service: service,
            subscriber,
            counters: RxCounters::default(),
            latest: None,
        })
    }

    /// Hands every queued sample, oldest first, to `f` (read in place in shared memory)
    /// and returns how many were drained. Never blocks or allocates; a receive error
    /// ends the drain and is counted.
    pub fn drain(&mut self, mut f: impl FnMut(&T)) -> usize {
        let mut n = 0;
        loop {
            match self.subscriber.receive() {
                Ok(Some(sample)) => {
                    let payload: &T = sample.payload();
                    f(payload);
                    self.latest = Some(*payload);
                    n += 1;
                }
                Ok(None) => break,
                Err(_) => {
                    self.counters.errors += 1;
                    break;
                }
            }
        }
        self.counters.received += n as u64;
        n
    }

    /// Drains the queue and returns the newest sample ever received (a copy), or `None`
    /// if nothing has arrived yet. Staleness is the caller's judgement (timestamps).
    pub fn latest(&mut self) -> Option<T> {
        self.drain(|_| {});
        self.latest
    }

    /// Receive counters.
    pub fn counters(&self) -> RxCounters {
        self.counters
    }
}

/// Object-state subscriber (ECU side).
pub type ObjectSubscriber = PolledSubscriber<ObjectState>;
/// Crash accelerometer subscriber (ECU side).
pub type AccelSubscriber = PolledSubscriber<CrashAccelSample>;
/// Diagnostics subscriber (monitor side).
pub type DiagnosticsSubscriber = PolledSubscriber<EcuDiagnostics>;
/// Bench-truth subscriber (actuator stubs, tests).
pub type BenchTruthSubscriber = PolledSubscriber<BenchTruth>;

impl BenchTruthSubscriber {
    /// Subscribes to the bench-truth service `names.bench_truth`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.bench_truth, &BENCH_TRUTH_PORTS)
    }
}

impl ObjectSubscriber {
    /// Subscribes to the object-state service `names.object_state`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.object_state, &OBJECT_STATE_PORTS)
    }
}

impl AccelSubscriber {
    /// Subscribes to the crash accelerometer service `names.crash_accel`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.crash_accel, &CRASH_ACCEL_PORTS)
    }
}

impl DiagnosticsSubscriber {
    /// Subscribes to the ECU diagnostics service `names.diagnostics`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.diagnostics, &DIAGNOSTICS_PORTS)
    }
}

/// Why a zero-copy publish failed (hot path: `Copy`, no text).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PublishError {
    /// No shared-memory chunk could be loaned.
    Loan(iceoryx2::port::LoanError),
    /// The sample could not be delivered.
    Send(iceoryx2::port::SendError),
}

/// Counters of a publisher.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TxCounters {
    /// Samples sent.
    pub sent: u64,
    /// Loan or send failures.
    pub errors: u64,
}

/// A typed zero-copy publisher: loan uninitialised shared memory, write in place, send.
pub struct ZeroCopyPublisher<T: fmt::Debug + ZeroCopySend + Copy + 'static> {
    _service: PubSubFactory<IpcService, T, ()>,
    publisher: Publisher<IpcService, T, ()>,
    counters: TxCounters,
}

impl<T: fmt::Debug + ZeroCopySend + Copy + 'static> ZeroCopyPublisher<T> {
    fn create(node: &IpcNode, name: &str, ports: &PortSettings) -> Result<Self, IpcError> {
        let service = open_service::<T>(node, name, ports)?;
        let publisher = service
            .publisher_builder()
            .create()
            .map_err(|e| setup_err("publisher creation", name, e))?;
        Ok(Self {
            _service: service,
            publisher,
            counters: TxCounters::default(),
        })
    }

    /// Loans a chunk, initialises it with `init` (one in-place write), lets `fill`
    /// complete it in place, and sends it. No allocation, no blocking.
    pub fn publish_with(&mut self, init: T, fill: impl FnOnce(&mut T)) -> Result<(), PublishError> {
        let result = self.publish_inner(init, fill);
        match result {
            Ok(()) => self.counters.sent += 1,
            Err(_) => self.counters.errors += 1,
        }
        result
    }

    fn publish_inner(&mut self, init: T, fill: impl FnOnce(&mut T)) -> Result<(), PublishError> {
        let sample = self.publisher.loan_uninit().map_err(PublishError::Loan)?;
        let mut sample = sample.write_payload(init);
        fill(sample.payload_mut());
        sample.send().map(|_| ()).map_err(PublishError::Send)
    }

    /// Publishes a copy of `value` (written straight into the loaned chunk).
    pub fn publish(&mut self, value: T) -> Result<(), PublishError> {
        self.publish_with(value, |_| {})
    }

    /// Send counters.
    pub fn counters(&self) -> TxCounters {
        self.counters
    }
}

/// Diagnostics publisher (ECU side).
pub type DiagnosticsPublisher = ZeroCopyPublisher<EcuDiagnostics>;
/// Object-state publisher (sensor-feed / test side).
pub type ObjectPublisher = ZeroCopyPublisher<ObjectState>;
/// Crash accelerometer publisher (sensor-feed / test side).
pub type AccelPublisher = ZeroCopyPublisher<CrashAccelSample>;
/// Bench-truth publisher (sensor-feed side).
pub type BenchTruthPublisher = ZeroCopyPublisher<BenchTruth>;

impl BenchTruthPublisher {
    /// Publishes on `names.bench_truth`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.bench_truth, &BENCH_TRUTH_PORTS)
    }
}

impl DiagnosticsPublisher {
    /// Publishes on `names.diagnostics`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.diagnostics, &DIAGNOSTICS_PORTS)
    }
}

impl ObjectPublisher {
    /// Publishes on `names.object_state`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.object_state, &OBJECT_STATE_PORTS)
    }
}

impl AccelPublisher {
    /// Publishes on `names.crash_accel`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        Self::create(node, &names.crash_accel, &CRASH_ACCEL_PORTS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unique_prefix(tag: &str) -> String {
        format!("ipc-test-{}-{tag}", std::process::id())
    }

    #[test]
    fn payloads_are_fixed_size_and_padding_free_where_it_matters() {
        // Sizes computed by hand from the field lists (repr(C), natural alignment).
        assert_eq!(
            core::mem::size_of::<ObjectState>(),
            8 + 8 + 6 * 4 + 4 + 1 + 3
        );
        assert_eq!(
            core::mem::size_of::<CrashAccelSample>(),
            8 + 8 + 4 + 4 + 8 * 4
        );
    }

    #[test]
    fn service_names_use_prefix_once() {
        let n = ServiceNames::with_prefix("x/");
        assert_eq!(n.object_state, "x/ecu/in/object_state");
        assert_eq!(n.crash_accel, "x/ecu/in/crash_accel");
        assert_eq!(n.diagnostics, "x/ecu/out/diagnostics");
        assert_eq!(n.bench_truth, "x/bench/truth");
    }

    #[test]
    fn bench_truth_name_roundtrip_and_truncation() {
        let mut t = BenchTruth::EMPTY;
        t.set_scenario_name("taurus-48-48-abs");
        assert_eq!(t.scenario_name(), "taurus-48-48-abs");
        // 63 ASCII bytes + a 2-byte character: truncated before the character.
        let long = format!("{}é", "a".repeat(63));
        t.set_scenario_name(&long);
        assert_eq!(t.scenario_name(), "a".repeat(63));
        t.scenario_name_len = u32::MAX;
        assert_eq!(t.scenario_name(), "a".repeat(63));
    }

    #[test]
    fn corrupt_accel_count_is_clamped() {
        let mut s = CrashAccelSample::EMPTY;
        s.count = u32::MAX;
        assert_eq!(s.samples().len(), ACCEL_BATCH_CAPACITY);
        s.count = 3;
        assert_eq!(s.samples().len(), 3);
    }

    #[test]
    fn mode_roundtrip() {
        for m in 0..=5u8 {
            assert_eq!(EcuMode::from_u8(m).map(|x| x as u8), Some(m));
        }
        assert_eq!(EcuMode::from_u8(6), None);
    }

    #[test]
    fn publish_subscribe_roundtrip_in_order() {
        let names = ServiceNames::with_prefix(&unique_prefix("rt"));
        let (node, _) = create_node("ipc-test", false).expect("node");
        let mut sub = ObjectSubscriber::new(&node, &names).expect("sub");
        let mut publ = ObjectPublisher::new(&node, &names).expect("pub");
        assert_eq!(sub.latest(), None);
        for seq in 1..=3u64 {
            publ.publish_with(ObjectState::INVALID, |o| {
                o.sequence = seq;
                o.distance_m = 10.0 * seq as f32;
                o.valid = VALID;
            })
            .expect("publish");
        }
        let mut seen = Vec::new();
        let n = sub.drain(|o| seen.push((o.sequence, o.distance_m)));
        assert_eq!(n, 3);
        assert_eq!(seen, vec![(1, 10.0), (2, 20.0), (3, 30.0)]);
        assert_eq!(sub.latest().map(|o| o.sequence), Some(3));
        assert_eq!(sub.counters().received, 3);
        assert_eq!(publ.counters().sent, 3);
    }

    #[test]
    fn accel_queue_overflow_keeps_newest() {
        let names = ServiceNames::with_prefix(&unique_prefix("ovf"));
        let (node, _) = create_node("ipc-test-ovf", false).expect("node");
        let mut sub = AccelSubscriber::new(&node, &names).expect("sub");
        let mut publ = AccelPublisher::new(&node, &names).expect("pub");
        let total = CRASH_ACCEL_PORTS.subscriber_buffer as u64 + 10;
        for seq in 1..=total {
            publ.publish_with(CrashAccelSample::EMPTY, |s| s.sequence = seq)
                .expect("publish");
        }
        let mut first = None;
        let mut last = 0;
        let n = sub.drain(|s| {
            first.get_or_insert(s.sequence);
            last = s.sequence;
        });
        assert_eq!(n, CRASH_ACCEL_PORTS.subscriber_buffer);
        assert_eq!(last, total);
        assert_eq!(
            first,
            Some(total - CRASH_ACCEL_PORTS.subscriber_buffer as u64 + 1)
        );
    }
}
