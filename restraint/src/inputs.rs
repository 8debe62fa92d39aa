//! Input monitoring: what the ECU believes about its inputs and how fresh that belief is.
//!
//! CAN frames go through the bus crate's [`E2eChecker`] (a stream that timed out is
//! resynchronised on its next frame); rejections feed the E2E burst window; object states are
//! checked for range, age and plausibility against the ego speed; accelerometer batches are
//! checked by the [`AccelMonitor`] (stale, stuck, saturated, out of range, non-monotonic time),
//! whose plausible samples go on to the crash detectors; iceoryx2 receive errors reported by
//! the shell are held for [`INVALID_HOLD_MS`]. [`InputMonitor::reasons`] turns all of it into
//! the degraded reasons of the cycle. Allocation-free: the burst window is a fixed-capacity
//! `heapless` queue.

use bus::codec::{
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass, V2xOpponentMassStationStatus,
};
use bus::{E2eChecker, Messages, RawFrame, RejectReason, CAN_EFF_FLAG};
use heapless::Deque;

use crate::accel::{AccelMonitor, PlausibleBatch, INVALID_HOLD_MS};
use crate::config::{CycleConfig, MAX_E2E_BURST};
use crate::contract::ReceiveErrors;
use crate::counters::CycleCounters;
use crate::settings::ms_to_ns;
use crate::signals::{CrashAccelSample, Degraded, ObjectState};
/// Closing speed above ego speed + this is implausible (opponent > 250 km/h), m/s.
const MAX_OPPONENT_SPEED_MPS: f32 = 70.0;
/// An object whose ground speed towards the ego is at most this stands, m/s: the object
/// sensor's closing-speed noise (0.2 m/s σ) with room, well below any moving traffic. A
/// standing object may be a wall, a pole or a parked truck, which the object sensor cannot
/// weigh (it reports a default mass).
pub const STANDING_SPEED_MPS: f32 = 2.0;

/// CAN ids the ECU consumes (kernel filter of the SocketCAN port), from the generated codec.
pub fn input_can_ids() -> [u32; 3] {
    [
        bus::EgoVehicleState::RAW_ID,
        bus::OccupantClassification::RAW_ID,
        bus::V2xOpponentMass::RAW_ID,
    ]
}

/// What the station ahead says of itself over V2X (`V2xOpponentMass`), as last received.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V2xStation {
    /// The station's own mass (load included), kg.
    pub mass_kg: f64,
    /// Range from the GNSS positions, m.
    pub range_m: f64,
    /// Closing speed from the GNSS velocities, m/s.
    pub closing_speed_mps: f64,
    /// When the frame was received, ns.
    pub rx_ns: u64,
}

/// Occupant as last reported on CAN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Occupant {
    /// Mass, kg.
    pub mass_kg: f32,
    /// Chest to wheel / airbag module, mm.
    pub chest_to_wheel_mm: f32,
    /// Belt buckled (the LUT is optimised for belted occupants; unbelted → reference).
    pub buckled: bool,
    /// An adult occupant the LUT covers (not empty, not a child seat).
    pub adult: bool,
}

/// The E2E failure burst: `count` rejections within `window_ns` set `E2E_FAILURE`, held until
/// `hold_ns` after the last rejection.
#[derive(Debug, Clone)]
struct E2eBurst {
    /// Times of the newest rejections, oldest first.
    recent_ns: Deque<u64, MAX_E2E_BURST>,
    count: usize,
    window_ns: u64,
    hold_ns: u64,
    active_until_ns: Option<u64>,
}

impl E2eBurst {
    fn note_rejection(&mut self, now: u64) {
        if self.recent_ns.is_full() {
            self.recent_ns.pop_front();
        }
        // Cannot fail: a slot was freed above.
        let _ = self.recent_ns.push_back(now);
        let len = self.recent_ns.storage_len();
        if len >= self.count {
            // The count-th newest rejection.
            let oldest = self.recent_ns.get(len - self.count).copied().unwrap_or(0);
            if now.saturating_sub(oldest) <= self.window_ns {
                self.active_until_ns = Some(now.saturating_add(self.hold_ns));
            }
        }
        if let Some(until) = self.active_until_ns {
            // A rejection while the burst is held extends the hold.
            if now <= until {
                self.active_until_ns = Some(now.saturating_add(self.hold_ns));
            }
        }
    }

    fn active(&self, now: u64) -> bool {
        self.active_until_ns.is_some_and(|t| now <= t)
    }
}

/// State of the input monitoring.
#[derive(Debug, Clone)]
pub struct InputMonitor {
    object_timeout_ns: u64,
    vehicle_timeout_ns: u64,
    occupant_timeout_ns: u64,
    hold_ns: u64,
    min_confidence: f64,

    checker: E2eChecker,
    burst: E2eBurst,

    /// Newest accepted object sample.
    pub(crate) object: ObjectState,
    /// The newest sample tracks an object (valid, confident).
    pub(crate) object_present: bool,
    /// The newest sample was implausible (until the next good one).
    pub(crate) object_invalid: bool,
    object_rx_ns: Option<u64>,
    /// A new object sample arrived this cycle.
    pub(crate) new_object: bool,
    /// The newest accepted object stands: its closing speed is the ego's own within
    /// [`STANDING_SPEED_MPS`] (`false` without a fresh vehicle frame).
    pub(crate) object_standing: bool,
    ego_speed_mps: f32,
    /// Newest `EgoLongAccel`, m/s² (negative = decelerating).
    ego_long_accel_mps2: f32,
    /// The newest `BrakeState` is not `Released`.
    ego_braking: bool,
    vehicle_rx_ns: Option<u64>,
    /// Occupant as last reported.
    pub(crate) occupant: Occupant,
    occupant_rx_ns: Option<u64>,
    /// The newest `V2xOpponentMass` with a station (`None`: never, or the newest said none).
    v2x: Option<V2xStation>,
    /// When the newest `V2xOpponentMass` (station or not) was accepted.
    v2x_rx_ns: Option<u64>,
    v2x_timeout_ns: u64,
    /// The occupant report changed this cycle.
    pub(crate) occupant_changed: bool,
    /// Sequence of the newest accelerometer batch.
    pub(crate) last_accel_sequence: u64,
    /// Plausibility and freshness of the crash accelerometer.
    pub(crate) accel: AccelMonitor,
    /// Plausibility and freshness of the safing accelerometer (the same checks, its range).
    pub(crate) safing: AccelMonitor,
    safing_rx_error_until_ns: Option<u64>,
    /// Receive errors reported by the I/O so far, and until when each port's are held.
    rx_errors: ReceiveErrors,
    object_rx_error_until_ns: Option<u64>,
    accel_rx_error_until_ns: Option<u64>,
}

impl InputMonitor {
    /// Monitoring with the timeouts of a validated `cfg`.
    pub fn new(cfg: &CycleConfig) -> Self {
        Self {
            object_timeout_ns: ms_to_ns(cfg.object_timeout_ms),
            vehicle_timeout_ns: ms_to_ns(cfg.vehicle_timeout_ms),
            occupant_timeout_ns: ms_to_ns(cfg.occupant_timeout_ms),
            hold_ns: ms_to_ns(INVALID_HOLD_MS),
            min_confidence: cfg.min_confidence,
            checker: E2eChecker::with_max_lost(cfg.e2e_max_lost),
            burst: E2eBurst {
                recent_ns: Deque::new(),
                count: (cfg.e2e_burst_count as usize).clamp(1, MAX_E2E_BURST),
                window_ns: ms_to_ns(cfg.e2e_burst_window_ms),
                hold_ns: ms_to_ns(cfg.e2e_hold_ms),
                active_until_ns: None,
            },
            object: ObjectState::INVALID,
            object_present: false,
            object_invalid: false,
            object_rx_ns: None,
            new_object: false,
            object_standing: false,
            ego_speed_mps: 0.0,
            ego_long_accel_mps2: 0.0,
            ego_braking: false,
            vehicle_rx_ns: None,
            occupant: Occupant {
                mass_kg: f32::NAN,
                chest_to_wheel_mm: f32::NAN,
                buckled: false,
                adult: false,
            },
            occupant_rx_ns: None,
            v2x: None,
            v2x_rx_ns: None,
            v2x_timeout_ns: ms_to_ns(cfg.v2x_timeout_ms),
            occupant_changed: false,
            last_accel_sequence: 0,
            accel: AccelMonitor::new(cfg.accel_limits()),
            safing: AccelMonitor::new(cfg.safing_limits()),
            safing_rx_error_until_ns: None,
            rx_errors: ReceiveErrors::default(),
            object_rx_error_until_ns: None,
            accel_rx_error_until_ns: None,
        }
    }

    /// Starts a cycle: nothing new yet.
    pub(crate) fn begin_cycle(&mut self) {
        self.new_object = false;
        self.occupant_changed = false;
    }

    /// E2E receive statistics.
    pub fn e2e_stats(&self) -> &bus::RxStats {
        self.checker.stats()
    }

    fn stale(rx: Option<u64>, now: u64, limit: u64) -> bool {
        rx.is_none_or(|t| now.saturating_sub(t) > limit)
    }

    /// An object sample (or a fresh "no track") has arrived at least once.
    pub(crate) fn objects_seen(&self) -> bool {
        self.object_rx_ns.is_some()
    }

    /// The ego vehicle frame is missing or older than its timeout.
    pub(crate) fn vehicle_stale(&self, now: u64) -> bool {
        Self::stale(self.vehicle_rx_ns, now, self.vehicle_timeout_ns)
    }

    /// The occupant frame is missing or older than its timeout.
    pub(crate) fn occupant_stale(&self, now: u64) -> bool {
        Self::stale(self.occupant_rx_ns, now, self.occupant_timeout_ns)
    }

    /// The occupant is known to be belted: a fresh occupant frame with the buckle closed. A
    /// missing or stale frame counts as unbelted, as a failed buckle switch does in production
    /// ECUs: the occupant who may be unbelted is never left without the airbag's lower line.
    pub(crate) fn occupant_belted(&self, now: u64) -> bool {
        self.occupant.buckled && !self.occupant_stale(now)
    }

    /// The station V2X reports, if its frame is fresh (`v2x_timeout_ms`). Optional equipment:
    /// no frame is no fault, only no second mass source.
    pub(crate) fn v2x_station(&self, now: u64) -> Option<&V2xStation> {
        self.v2x
            .as_ref()
            .filter(|v| !Self::stale(Some(v.rx_ns), now, self.v2x_timeout_ns))
    }

    /// One received CAN frame.
    pub(crate) fn on_can(&mut self, f: &RawFrame, now: u64, counters: &mut CycleCounters) {
        counters.can_frames_rx = counters.can_frames_rx.saturating_add(1);
        if f.id & CAN_EFF_FLAG != 0 {
            return; // never ours; the kernel filter drops them on a real bus
        }
        // A stream that timed out starts a new counter sequence (e.g. its sender restarted):
        // resynchronise on its first frame instead of rejecting it.
        let resync = match f.id {
            bus::EgoVehicleState::RAW_ID => self.vehicle_stale(now),
            bus::OccupantClassification::RAW_ID => self.occupant_stale(now),
            bus::V2xOpponentMass::RAW_ID => Self::stale(self.v2x_rx_ns, now, self.v2x_timeout_ns),
            _ => false,
        };
        let checked = if resync {
            self.checker.check_resync(f.id, f.payload())
        } else {
            self.checker.check(f.id, f.payload())
        };
        match checked {
            Ok(Messages::EgoVehicleState(m)) => {
                self.ego_speed_mps = m.ego_speed();
                self.ego_long_accel_mps2 = m.ego_long_accel();
                self.ego_braking = m.brake_state() != EgoVehicleStateBrakeState::Released;
                self.vehicle_rx_ns = Some(now);
            }
            Ok(Messages::OccupantClassification(m)) => {
                let occ = Occupant {
                    mass_kg: m.occupant_mass(),
                    chest_to_wheel_mm: f32::from(m.chest_to_wheel()),
                    buckled: m.belt_buckle() == OccupantClassificationBeltBuckle::Buckled,
                    adult: matches!(
                        m.occupant_class(),
                        OccupantClassificationOccupantClass::SmallAdult
                            | OccupantClassificationOccupantClass::MidAdult
                            | OccupantClassificationOccupantClass::LargeAdult
                    ),
                };
                self.occupant_changed |= occ != self.occupant;
                self.occupant = occ;
                self.occupant_rx_ns = Some(now);
            }
            Ok(Messages::V2xOpponentMass(m)) => {
                // The codec's ranges hold (out-of-range frames are rejected above): a station
                // that reports no mass says nothing about the opponent's.
                let mass_kg = f64::from(m.opponent_mass());
                self.v2x_rx_ns = Some(now);
                self.v2x = (m.station_status() == V2xOpponentMassStationStatus::Valid
                    && mass_kg > 0.0)
                    .then_some(V2xStation {
                        mass_kg,
                        range_m: f64::from(m.station_range()),
                        closing_speed_mps: f64::from(m.closing_speed()),
                        rx_ns: now,
                    });
            }
            Ok(_) => {}
            Err(e) if e.reason() == RejectReason::UnknownId => {}
            Err(_) => self.burst.note_rejection(now),
        }
    }

    /// Whether `o` is plausible (`vehicle_fresh`: the vehicle frame is fresh, so its ego speed
    /// bounds the closing speed).
    fn object_plausible(&self, o: &ObjectState, now: u64, vehicle_fresh: bool) -> bool {
        let f = [
            o.distance_m,
            o.closing_speed_mps,
            o.relative_accel_mps2,
            o.opponent_mass_kg,
            o.opponent_mass_sigma_kg,
            o.confidence,
        ];
        if !f.iter().all(|v| v.is_finite()) {
            return false;
        }
        let ranges_ok = (-5.0..=300.0).contains(&o.distance_m)
            && (-100.0..=100.0).contains(&o.closing_speed_mps)
            && (-300.0..=300.0).contains(&o.relative_accel_mps2)
            && (100.0..=60_000.0).contains(&o.opponent_mass_kg)
            && (0.0..=10_000.0).contains(&o.opponent_mass_sigma_kg)
            && (0.0..=1.0).contains(&o.confidence);
        // The measurement must be recent on our clock (same CLOCK_MONOTONIC on the bench).
        let age_ok = now.abs_diff(o.timestamp_ns) <= self.object_timeout_ns;
        let speed_ok =
            !vehicle_fresh || o.closing_speed_mps <= self.ego_speed_mps + MAX_OPPONENT_SPEED_MPS;
        ranges_ok && age_ok && speed_ok
    }

    /// One received object state.
    pub(crate) fn on_object(&mut self, o: &ObjectState, now: u64, counters: &mut CycleCounters) {
        counters.objects_rx = counters.objects_rx.saturating_add(1);
        if !o.is_valid() {
            // A "no track" record is information too, and can be as old as any other: a
            // stuck sensor repeating its last "nothing ahead" must go stale like any sample.
            if now.abs_diff(o.timestamp_ns) > self.object_timeout_ns {
                counters.objects_invalid = counters.objects_invalid.saturating_add(1);
                self.object_invalid = true;
                return;
            }
            // A fresh "no track" sample: the sensor is alive, nothing ahead.
            self.object_present = false;
            self.object_invalid = false;
            self.object_rx_ns = Some(now);
            self.object = *o;
            self.new_object = true;
            return;
        }
        // The ego speed of a fresh vehicle frame bounds the closing speed and says whether the
        // object stands: one freshness check for both.
        let vehicle_fresh = !self.vehicle_stale(now);
        if self.object_plausible(o, now, vehicle_fresh) {
            self.object_standing = vehicle_fresh
                && (o.closing_speed_mps - self.ego_speed_mps).abs() <= STANDING_SPEED_MPS;
            self.object = *o;
            self.object_present = f64::from(o.confidence) >= self.min_confidence;
            self.object_invalid = false;
            self.object_rx_ns = Some(now);
            self.new_object = true;
        } else {
            counters.objects_invalid = counters.objects_invalid.saturating_add(1);
            self.object_invalid = true;
        }
    }

    /// One received accelerometer batch: checked by the [`AccelMonitor`], its plausible
    /// samples put into `out` in time order.
    pub(crate) fn on_accel(
        &mut self,
        a: &CrashAccelSample,
        now: u64,
        counters: &mut CycleCounters,
        out: &mut PlausibleBatch,
    ) {
        counters.accel_batches_rx = counters.accel_batches_rx.saturating_add(1);
        let s = a.samples();
        counters.accel_samples_rx = counters.accel_samples_rx.saturating_add(s.len() as u64);
        self.last_accel_sequence = a.sequence;
        self.accel
            .feed(now, a.first_timestamp_ns, a.sample_period_ns, s, out);
    }

    /// One received safing-accelerometer batch: checked by its own [`AccelMonitor`], its
    /// plausible samples put into `out` in time order.
    pub(crate) fn on_safing(&mut self, a: &CrashAccelSample, now: u64, out: &mut PlausibleBatch) {
        self.safing.feed(
            now,
            a.first_timestamp_ns,
            a.sample_period_ns,
            a.samples(),
            out,
        );
    }

    /// The I/O's receive-error totals at `now`: new errors on a port hold its fault.
    pub(crate) fn on_receive_errors(&mut self, e: ReceiveErrors, now: u64) {
        let until = Some(now.saturating_add(self.hold_ns));
        if e.objects > self.rx_errors.objects {
            self.object_rx_error_until_ns = until;
        }
        if e.accel > self.rx_errors.accel {
            self.accel_rx_error_until_ns = until;
        }
        if e.safing > self.rx_errors.safing {
            self.safing_rx_error_until_ns = until;
        }
        self.rx_errors = e;
    }

    /// Receive errors on the object port within the hold time.
    pub(crate) fn object_port_error(&self, now: u64) -> bool {
        self.object_rx_error_until_ns.is_some_and(|t| now <= t)
    }

    /// Receive errors on the accelerometer port within the hold time.
    pub(crate) fn accel_port_error(&self, now: u64) -> bool {
        self.accel_rx_error_until_ns.is_some_and(|t| now <= t)
    }

    /// The newest vehicle-dynamics deceleration (m/s², positive = slowing down) and when it was
    /// received, if the vehicle frame is fresh.
    pub(crate) fn vehicle_decel(&self, now: u64) -> Option<(f64, u64)> {
        let rx = self.vehicle_rx_ns.filter(|_| !self.vehicle_stale(now))?;
        Some((-f64::from(self.ego_long_accel_mps2), rx))
    }

    /// The deceleration the car's own braking explains, m/s²: the fresh vehicle frame's
    /// deceleration while its brake state says braking, within [0, `max_mps2`]; 0 otherwise
    /// (no brake, stale frame, NaN).
    pub(crate) fn braking_decel(&self, now: u64, max_mps2: f64) -> f64 {
        // Every cycle of a drive asks: the common answer (not braking) without the clock.
        if !(self.ego_braking && self.ego_long_accel_mps2 < 0.0) {
            return 0.0;
        }
        self.vehicle_decel(now)
            .map_or(0.0, |(d, _)| d.min(max_mps2))
    }

    /// The degraded reasons at `now` (`lut_present`: a usable LUT was loaded).
    pub(crate) fn reasons(&self, now: u64, can_on: bool, lut_present: bool) -> Degraded {
        let mut r = Degraded::empty();
        r.set(
            Degraded::OBJECT_STALE,
            Self::stale(self.object_rx_ns, now, self.object_timeout_ns),
        );
        r.set(Degraded::OBJECT_INVALID, self.object_invalid);
        r.set(Degraded::ACCEL_INVALID, self.accel.invalid(now));
        r.set(Degraded::ACCEL_STALE, self.accel.stale(now));
        r.set(Degraded::SAFING_STALE, self.safing.stale(now));
        r.set(
            Degraded::SAFING_INVALID,
            self.safing.invalid(now) || self.safing_rx_error_until_ns.is_some_and(|t| now <= t),
        );
        r.set(
            Degraded::IPC_ERROR,
            self.object_port_error(now) || self.accel_port_error(now),
        );
        if can_on {
            r.set(
                Degraded::CAN_STALE,
                self.vehicle_stale(now) || self.occupant_stale(now),
            );
        } else {
            r |= Degraded::CAN_DISABLED;
        }
        r.set(Degraded::E2E_FAILURE, self.burst.active(now));
        r.set(Degraded::LUT_INVALID, !lut_present);
        r
    }
}
