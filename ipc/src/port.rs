//! Node and port plumbing: one generic subscriber and one generic publisher over a [`Topic`]
//! (payload, value, service name, port settings), instead of one constructor per service.

use core::fmt;

use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use signals::{CrashAccelSample, EcuDiagnostics, ObjectState, SatelliteFrames};

use crate::names::{
    PortSettings, ServiceNames, BENCH_TRUTH_PORTS, CRASH_ACCEL_PORTS, DIAGNOSTICS_PORTS,
    OBJECT_STATE_PORTS, SAFING_ACCEL_PORTS, SATELLITE_PORTS,
};
use crate::payload::{BenchTruth, Shm};

/// The iceoryx2 service flavour used by the bench: inter-process shared memory.
pub type IpcService = iceoryx2::service::ipc::Service;
/// A node of the bench's iceoryx2 flavour.
pub type IpcNode = Node<IpcService>;

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

/// One publish-subscribe service of the bench: what the processes read and write, what
/// iceoryx2 carries, and where.
pub trait Topic {
    /// What the processes read and write.
    type Value: Copy + fmt::Debug + 'static;
    /// What iceoryx2 carries (same layout as `Value`).
    type Payload: ZeroCopySend + Copy + fmt::Debug + 'static;
    /// Port settings every opener requests.
    const PORTS: PortSettings;
    /// The service's name under `names`.
    fn service_name(names: &ServiceNames) -> &str;
    /// Value → payload.
    fn wrap(v: Self::Value) -> Self::Payload;
    /// The value inside a payload.
    fn value(p: &Self::Payload) -> &Self::Value;
    /// The value inside a payload, writable.
    fn value_mut(p: &mut Self::Payload) -> &mut Self::Value;
    /// The service opened (or created) under `names` and a subscriber on it.
    fn subscribe(node: &IpcNode, names: &ServiceNames) -> Result<SubscriberPort<Self>, IpcError>
    where
        Self: Sized;
    /// The service opened (or created) under `names` and a publisher on it.
    fn publisher(node: &IpcNode, names: &ServiceNames) -> Result<PublisherPort<Self>, IpcError>
    where
        Self: Sized;
}

/// A topic's service and a subscriber on it.
pub type SubscriberPort<T> = (
    PubSubFactory<IpcService, <T as Topic>::Payload, ()>,
    Subscriber<IpcService, <T as Topic>::Payload, ()>,
);
/// A topic's service and a publisher on it.
pub type PublisherPort<T> = (
    PubSubFactory<IpcService, <T as Topic>::Payload, ()>,
    Publisher<IpcService, <T as Topic>::Payload, ()>,
);

/// [`Topic::subscribe`] and [`Topic::publisher`] of one topic: written in each topic's own
/// `impl` so that they are ordinary (non-generic) functions of this crate. iceoryx2's service,
/// subscriber and publisher builders are generic over the payload, and a release build does not
/// share generic instances between crates: as generic code here, every crate that opened a port
/// (the ECU, feeds, stubs, each test binary) compiled its own copy of them.
macro_rules! port_openers {
    () => {
        fn subscribe(
            node: &IpcNode,
            names: &ServiceNames,
        ) -> Result<SubscriberPort<Self>, IpcError> {
            subscribe_to::<Self>(node, names)
        }
        fn publisher(
            node: &IpcNode,
            names: &ServiceNames,
        ) -> Result<PublisherPort<Self>, IpcError> {
            publish_on::<Self>(node, names)
        }
    };
}

macro_rules! shm_topic {
    ($(#[$doc:meta])* $topic:ident, $value:ty, $ports:expr, $field:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy)]
        pub struct $topic;
        impl Topic for $topic {
            type Value = $value;
            type Payload = Shm<$value>;
            const PORTS: PortSettings = $ports;
            fn service_name(names: &ServiceNames) -> &str {
                &names.$field
            }
            fn wrap(v: $value) -> Shm<$value> {
                Shm(v)
            }
            fn value(p: &Shm<$value>) -> &$value {
                &p.0
            }
            fn value_mut(p: &mut Shm<$value>) -> &mut $value {
                &mut p.0
            }
            port_openers!();
        }
    };
}

shm_topic!(
    /// Opponent-object state (sensor feeds → ECU).
    ObjectTopic, ObjectState, OBJECT_STATE_PORTS, object_state
);
shm_topic!(
    /// Compartment crash accelerometer (sensor feeds → ECU).
    AccelTopic, CrashAccelSample, CRASH_ACCEL_PORTS, crash_accel
);
shm_topic!(
    /// Safing accelerometer (sensor feeds → ECU): the crash accelerometer's record on its own
    /// service.
    SafingTopic, CrashAccelSample, SAFING_ACCEL_PORTS, safing_accel
);
shm_topic!(
    /// The left crush-zone satellite's PSI5 frames (sensor feeds → ECU).
    SatelliteLeftTopic, SatelliteFrames, SATELLITE_PORTS, satellite_left
);
shm_topic!(
    /// The right crush-zone satellite's PSI5 frames (sensor feeds → ECU).
    SatelliteRightTopic, SatelliteFrames, SATELLITE_PORTS, satellite_right
);
shm_topic!(
    /// ECU diagnostics (ECU → monitors).
    DiagnosticsTopic, EcuDiagnostics, DIAGNOSTICS_PORTS, diagnostics
);

/// Bench truth (sensor feeds → actuator stubs; never read by the ECU).
#[derive(Debug, Clone, Copy)]
pub struct BenchTruthTopic;
impl Topic for BenchTruthTopic {
    type Value = BenchTruth;
    type Payload = BenchTruth;
    const PORTS: PortSettings = BENCH_TRUTH_PORTS;
    fn service_name(names: &ServiceNames) -> &str {
        &names.bench_truth
    }
    fn wrap(v: BenchTruth) -> BenchTruth {
        v
    }
    fn value(p: &BenchTruth) -> &BenchTruth {
        p
    }
    fn value_mut(p: &mut BenchTruth) -> &mut BenchTruth {
        p
    }
    port_openers!();
}

fn open_service<T: Topic>(
    node: &IpcNode,
    names: &ServiceNames,
) -> Result<PubSubFactory<IpcService, T::Payload, ()>, IpcError> {
    let name = T::service_name(names);
    let ports = T::PORTS;
    let service_name = ServiceName::new(name).map_err(|e| IpcError::ServiceName {
        name: name.to_owned(),
        detail: format!("{e:?}"),
    })?;
    node.service_builder(&service_name)
        .publish_subscribe::<T::Payload>()
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

fn subscribe_to<T: Topic>(
    node: &IpcNode,
    names: &ServiceNames,
) -> Result<SubscriberPort<T>, IpcError> {
    let service = open_service::<T>(node, names)?;
    let subscriber = service
        .subscriber_builder()
        .buffer_size(T::PORTS.subscriber_buffer)
        .create()
        .map_err(|e| setup_err("subscriber creation", T::service_name(names), e))?;
    Ok((service, subscriber))
}

fn publish_on<T: Topic>(
    node: &IpcNode,
    names: &ServiceNames,
) -> Result<PublisherPort<T>, IpcError> {
    let service = open_service::<T>(node, names)?;
    let publisher = service
        .publisher_builder()
        .create()
        .map_err(|e| setup_err("publisher creation", T::service_name(names), e))?;
    Ok((service, publisher))
}

/// Counters of a polled subscriber (hot path: counts only, never formats).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RxCounters {
    /// Samples received since creation.
    pub received: u64,
    /// `receive()` calls that returned an error.
    pub errors: u64,
}

/// A poll-only typed subscriber.
pub struct PolledSubscriber<T: Topic> {
    _service: PubSubFactory<IpcService, T::Payload, ()>,
    subscriber: Subscriber<IpcService, T::Payload, ()>,
    counters: RxCounters,
    latest: Option<T::Value>,
}

impl<T: Topic> PolledSubscriber<T> {
    /// Subscribes to the topic's service under `names`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        let (service, subscriber) = T::subscribe(node, names)?;
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
    pub fn drain(&mut self, mut f: impl FnMut(&T::Value)) -> usize {
        let mut n = 0;
        loop {
            match self.subscriber.receive() {
                Ok(Some(sample)) => {
                    let value = T::value(sample.payload());
                    f(value);
                    self.latest = Some(*value);
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
    pub fn latest(&mut self) -> Option<T::Value> {
        self.drain(|_| {});
        self.latest
    }

    /// Receive counters.
    pub fn counters(&self) -> RxCounters {
        self.counters
    }
}

/// Object-state subscriber (ECU side).
pub type ObjectSubscriber = PolledSubscriber<ObjectTopic>;
/// Crash accelerometer subscriber (ECU side).
pub type AccelSubscriber = PolledSubscriber<AccelTopic>;
/// Safing accelerometer subscriber (ECU side).
pub type SafingSubscriber = PolledSubscriber<SafingTopic>;
/// Left satellite subscriber (ECU side).
pub type SatelliteLeftSubscriber = PolledSubscriber<SatelliteLeftTopic>;
/// Right satellite subscriber (ECU side).
pub type SatelliteRightSubscriber = PolledSubscriber<SatelliteRightTopic>;
/// Diagnostics subscriber (monitor side).
pub type DiagnosticsSubscriber = PolledSubscriber<DiagnosticsTopic>;
/// Bench-truth subscriber (actuator stubs, tests).
pub type BenchTruthSubscriber = PolledSubscriber<BenchTruthTopic>;

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
pub struct ZeroCopyPublisher<T: Topic> {
    _service: PubSubFactory<IpcService, T::Payload, ()>,
    publisher: Publisher<IpcService, T::Payload, ()>,
    counters: TxCounters,
}

impl<T: Topic> ZeroCopyPublisher<T> {
    /// Publishes on the topic's service under `names`.
    pub fn new(node: &IpcNode, names: &ServiceNames) -> Result<Self, IpcError> {
        let (service, publisher) = T::publisher(node, names)?;
        Ok(Self {
            _service: service,
            publisher,
            counters: TxCounters::default(),
        })
    }

    /// Loans a chunk, initialises it with `init` (one in-place write), lets `fill`
    /// complete it in place, and sends it. No allocation, no blocking.
    pub fn publish_with(
        &mut self,
        init: T::Value,
        fill: impl FnOnce(&mut T::Value),
    ) -> Result<(), PublishError> {
        let result = self.publish_inner(init, fill);
        match result {
            Ok(()) => self.counters.sent += 1,
            Err(_) => self.counters.errors += 1,
        }
        result
    }

    fn publish_inner(
        &mut self,
        init: T::Value,
        fill: impl FnOnce(&mut T::Value),
    ) -> Result<(), PublishError> {
        let sample = self.publisher.loan_uninit().map_err(PublishError::Loan)?;
        let mut sample = sample.write_payload(T::wrap(init));
        fill(T::value_mut(sample.payload_mut()));
        sample.send().map(|_| ()).map_err(PublishError::Send)
    }

    /// Publishes a copy of `value` (written straight into the loaned chunk).
    pub fn publish(&mut self, value: T::Value) -> Result<(), PublishError> {
        self.publish_with(value, |_| {})
    }

    /// Send counters.
    pub fn counters(&self) -> TxCounters {
        self.counters
    }
}

/// Diagnostics publisher (ECU side).
pub type DiagnosticsPublisher = ZeroCopyPublisher<DiagnosticsTopic>;
/// Object-state publisher (sensor-feed / test side).
pub type ObjectPublisher = ZeroCopyPublisher<ObjectTopic>;
/// Crash accelerometer publisher (sensor-feed / test side).
pub type AccelPublisher = ZeroCopyPublisher<AccelTopic>;
/// Safing accelerometer publisher (sensor-feed / test side).
pub type SafingPublisher = ZeroCopyPublisher<SafingTopic>;
/// Left satellite publisher (sensor-feed / test side).
pub type SatelliteLeftPublisher = ZeroCopyPublisher<SatelliteLeftTopic>;
/// Right satellite publisher (sensor-feed / test side).
pub type SatelliteRightPublisher = ZeroCopyPublisher<SatelliteRightTopic>;
/// Bench-truth publisher (sensor-feed side).
pub type BenchTruthPublisher = ZeroCopyPublisher<BenchTruthTopic>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::CRASH_ACCEL_PORTS;
    use signals::VALID;

    fn unique_prefix(tag: &str) -> String {
        format!("ipc-test-{}-{tag}", std::process::id())
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

    #[test]
    fn safing_and_crash_accelerometers_are_separate_services() {
        let names = ServiceNames::with_prefix(&unique_prefix("safing"));
        let (node, _) = create_node("ipc-test-safing", false).expect("node");
        let mut crash_sub = AccelSubscriber::new(&node, &names).expect("crash sub");
        let mut safing_sub = SafingSubscriber::new(&node, &names).expect("safing sub");
        let mut crash_pub = AccelPublisher::new(&node, &names).expect("crash pub");
        let mut safing_pub = SafingPublisher::new(&node, &names).expect("safing pub");
        for seq in 1..=3u64 {
            safing_pub
                .publish_with(CrashAccelSample::EMPTY, |s| {
                    s.sequence = seq;
                    s.count = 1;
                    s.accel_mps2[0] = -10.0 * seq as f32;
                })
                .expect("publish");
        }
        crash_pub
            .publish_with(CrashAccelSample::EMPTY, |s| s.sequence = 100)
            .expect("publish");
        let mut safing = Vec::new();
        assert_eq!(
            safing_sub.drain(|s| safing.push((s.sequence, s.accel_mps2[0]))),
            3
        );
        assert_eq!(safing, vec![(1, -10.0), (2, -20.0), (3, -30.0)]);
        let mut crash = Vec::new();
        assert_eq!(crash_sub.drain(|s| crash.push(s.sequence)), 1);
        assert_eq!(crash, vec![100]);
        assert_eq!(safing_sub.counters().received, 3);
    }
}
