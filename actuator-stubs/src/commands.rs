//! What the modules received and did: decoded command records (one JSONL line each) and the
//! actuator state machines that turn them into actions at their receive times.
//!
//! Acting rule: the ECU is the timer. A module acts when the command that requests the action
//! arrives (pretensioner `Fire`/`Release`; airbag `Fire` while `Armed`); the `…FireTime` signals
//! (planned times relative to the *predicted* contact) are logged and compared, not re-timed,
//! because the module has no notion of the predicted contact.

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, BeltLimiterCmdCmdSource,
    BeltLimiterCmdPretensionerCmd,
};
use bus::Messages;
use serde::{Deserialize, Serialize};

/// One received frame, decoded (JSONL record of the command log).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct CommandRecord {
    /// CLOCK_MONOTONIC receive time [ns] (kernel arrival time mapped onto CLOCK_MONOTONIC when
    /// the kernel gave one, else the time the read returned).
    pub rx_mono_ns: u64,
    /// CAN id.
    pub id: u32,
    /// DBC message name (or "unknown").
    pub message: String,
    /// Payload bytes, hex.
    pub data_hex: String,
    /// "ok" or the E2E/decoding rejection reason.
    pub e2e: String,
    /// SecOC verdict (command and authenticator frames only): "held", "ok" or the
    /// rejection reason; see [`crate::rx`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub secoc: Option<String>,
    /// Decoded physical values (accepted frames only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decoded: Option<Decoded>,
}

/// Decoded content of the frames the modules act on.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Decoded {
    /// `BeltLimiterCmd`.
    Belt {
        /// "idle" | "fire" | "release".
        pretensioner: String,
        /// "adaptive" | "reference".
        source: String,
        /// Load-limiter level [kN].
        load_limiter_kn: f64,
        /// Planned pretensioner time relative to the predicted contact [ms].
        pretensioner_fire_time_ms: f64,
    },
    /// `AirbagStageCmd`.
    Airbag {
        /// Armed.
        armed: bool,
        /// Fire requested.
        fire: bool,
        /// "adaptive" | "reference".
        source: String,
        /// Stage raw value (0 none, 1, 2, 3 both).
        stage: u8,
        /// Force level [kN].
        force_level_kn: f64,
        /// Planned fire time relative to the predicted contact [ms].
        fire_time_ms: f64,
    },
    /// `EcuStatus`.
    Status {
        /// ECU mode raw value (DBC `EcuMode`, named by `bus::EcuStatus::ECU_MODE_VALUES`).
        mode: u8,
        /// The frame's fault flags (why the ECU degraded): bit k = the k-th `Fault…` signal of
        /// the DBC ([`crate::status::ecu_fault_signals`]).
        faults: u16,
    },
    /// Any other accepted frame (authenticators, foreign frames).
    Other,
}

/// Decodes an accepted message into a [`Decoded`].
pub fn decode(msg: &Messages) -> Decoded {
    match msg {
        Messages::BeltLimiterCmd(m) => Decoded::Belt {
            pretensioner: match m.pretensioner_cmd() {
                BeltLimiterCmdPretensionerCmd::Fire => "fire",
                BeltLimiterCmdPretensionerCmd::Release => "release",
                _ => "idle",
            }
            .into(),
            source: match m.cmd_source() {
                BeltLimiterCmdCmdSource::Reference => "reference",
                _ => "adaptive",
            }
            .into(),
            load_limiter_kn: round3(f64::from(m.load_limiter_level())),
            pretensioner_fire_time_ms: round3(f64::from(m.pretensioner_fire_time())),
        },
        Messages::AirbagStageCmd(m) => Decoded::Airbag {
            armed: matches!(m.arm(), AirbagStageCmdArm::Armed),
            fire: matches!(m.fire(), AirbagStageCmdFire::Fire),
            source: match m.cmd_source() {
                AirbagStageCmdCmdSource::Reference => "reference",
                _ => "adaptive",
            }
            .into(),
            stage: u8::from(m.stage()),
            force_level_kn: round3(f64::from(m.force_level())),
            fire_time_ms: round3(f64::from(m.fire_time())),
        },
        Messages::EcuStatus(m) => {
            let mut values = [0.0f64; 16];
            let n = bus::signal_values(msg, &mut values).unwrap_or(0);
            Decoded::Status {
                mode: u8::from(m.ecu_mode()),
                faults: crate::status::ecu_fault_indices()
                    .enumerate()
                    .filter(|(_, i)| *i < n && values.get(*i).is_some_and(|v| *v != 0.0))
                    .fold(0, |bits, (k, _)| bits | (1 << k)),
            }
        }
        _ => Decoded::Other,
    }
}

fn round3(v: f64) -> f64 {
    (v * 1e3).round() / 1e3
}

/// An action a module performed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Action {
    /// CLOCK_MONOTONIC time of the action (= receive time of the command) [ns].
    pub t_ns: u64,
    /// "pretensioner_fire" | "pretensioner_release" | "airbag_fire" | "airbag_fire_ignored_disarmed".
    pub what: String,
    /// Level in force [kN] (load limiter or airbag level).
    pub level_kn: f64,
    /// Planned time from the command relative to the predicted contact [ms].
    pub planned_ms: f64,
    /// "adaptive" | "reference".
    pub source: String,
}

/// Belt retractor + airbag module state machines.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Modules {
    /// Pretensioner currently fired (slack removed).
    pub pretensioner_fired: bool,
    /// Airbag fired (irreversible).
    pub airbag_fired: bool,
    /// Every action, in order.
    pub actions: Vec<Action>,
    /// Load-limiter level history: (t_ns, kN).
    pub limiter_levels: Vec<(u64, f64)>,
    /// Receive times of belt commands whose source is the adaptive plan [ns] (the first one
    /// after the threat is the preset, whether or not its level differs from the last one).
    pub adaptive_belt_cmds: Vec<u64>,
    /// ECU mode changes seen on EcuStatus: (t_ns, mode).
    pub ecu_modes: Vec<(u64, u8)>,
    /// ECU fault-flag changes seen on EcuStatus: (t_ns, flags as in [`Decoded::Status`]).
    pub ecu_faults: Vec<(u64, u16)>,
    /// First command (belt or airbag) whose source is the reference restraint [ns].
    pub first_reference_cmd_ns: Option<u64>,
    /// First airbag command with `Arm = Armed` [ns].
    pub first_armed_ns: Option<u64>,
}

impl Modules {
    /// Applies one accepted command received at `t_ns`.
    pub fn apply(&mut self, t_ns: u64, d: &Decoded) {
        match d {
            Decoded::Belt {
                pretensioner,
                source,
                load_limiter_kn,
                pretensioner_fire_time_ms,
            } => {
                if source == "reference" {
                    self.first_reference_cmd_ns.get_or_insert(t_ns);
                }
                if source == "adaptive" && self.adaptive_belt_cmds.last() != Some(&t_ns) {
                    self.adaptive_belt_cmds.push(t_ns);
                }
                if self.limiter_levels.last().map(|l| l.1) != Some(*load_limiter_kn) {
                    self.limiter_levels.push((t_ns, *load_limiter_kn));
                }
                match pretensioner.as_str() {
                    "fire" if !self.pretensioner_fired => {
                        self.pretensioner_fired = true;
                        self.actions.push(Action {
                            t_ns,
                            what: "pretensioner_fire".into(),
                            level_kn: *load_limiter_kn,
                            planned_ms: *pretensioner_fire_time_ms,
                            source: source.clone(),
                        });
                    }
                    "release" if self.pretensioner_fired => {
                        self.pretensioner_fired = false;
                        self.actions.push(Action {
                            t_ns,
                            what: "pretensioner_release".into(),
                            level_kn: *load_limiter_kn,
                            planned_ms: *pretensioner_fire_time_ms,
                            source: source.clone(),
                        });
                    }
                    _ => {}
                }
            }
            Decoded::Airbag {
                armed,
                fire,
                source,
                force_level_kn,
                fire_time_ms,
                ..
            } => {
                if source == "reference" {
                    self.first_reference_cmd_ns.get_or_insert(t_ns);
                }
                if *armed {
                    self.first_armed_ns.get_or_insert(t_ns);
                }
                if *fire && !self.airbag_fired {
                    let what = if *armed {
                        self.airbag_fired = true;
                        "airbag_fire"
                    } else {
                        "airbag_fire_ignored_disarmed"
                    };
                    if *armed || !self.actions.iter().any(|a| a.what == what) {
                        self.actions.push(Action {
                            t_ns,
                            what: what.into(),
                            level_kn: *force_level_kn,
                            planned_ms: *fire_time_ms,
                            source: source.clone(),
                        });
                    }
                }
            }
            Decoded::Status { mode, faults } => {
                if self.ecu_modes.last().map(|m| m.1) != Some(*mode) {
                    self.ecu_modes.push((t_ns, *mode));
                }
                if self.ecu_faults.last().map_or(0, |f| f.1) != *faults {
                    self.ecu_faults.push((t_ns, *faults));
                }
            }
            Decoded::Other => {}
        }
    }

    /// The first action named `what`.
    pub fn action(&self, what: &str) -> Option<&Action> {
        self.actions.iter().find(|a| a.what == what)
    }

    /// The load-limiter level in force at `t_ns` (last level received at or before it; if none
    /// yet, the first one received afterwards).
    pub fn limiter_at(&self, t_ns: u64) -> Option<f64> {
        self.limiter_levels
            .iter()
            .rev()
            .find(|l| l.0 <= t_ns)
            .or_else(|| self.limiter_levels.first())
            .map(|l| l.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn belt(p: &str, kn: f64) -> Decoded {
        Decoded::Belt {
            pretensioner: p.into(),
            source: "adaptive".into(),
            load_limiter_kn: kn,
            pretensioner_fire_time_ms: -30.0,
        }
    }
    fn bag(armed: bool, fire: bool, kn: f64) -> Decoded {
        Decoded::Airbag {
            armed,
            fire,
            source: "adaptive".into(),
            stage: 1,
            force_level_kn: kn,
            fire_time_ms: 12.0,
        }
    }

    #[test]
    fn adaptive_belt_commands_are_recorded_even_when_the_level_does_not_change() {
        // The e2e bench found a plan whose limiter level equalled the level already on the
        // bus: the preset must still be seen (it is the adaptive command, not a level change).
        let mut m = Modules::default();
        let reference = Decoded::Belt {
            pretensioner: "idle".into(),
            source: "reference".into(),
            load_limiter_kn: 12.0,
            pretensioner_fire_time_ms: 10.0,
        };
        m.apply(10, &reference);
        m.apply(20, &belt("idle", 12.0));
        m.apply(30, &belt("idle", 12.0));
        assert_eq!(m.limiter_levels, vec![(10, 12.0)]);
        assert_eq!(m.adaptive_belt_cmds, vec![20, 30]);
        assert_eq!(m.first_reference_cmd_ns, Some(10));
    }

    #[test]
    fn pretensioner_fires_once_and_releases() {
        let mut m = Modules::default();
        m.apply(10, &belt("idle", 4.0));
        m.apply(20, &belt("fire", 4.0));
        m.apply(30, &belt("fire", 4.5));
        m.apply(40, &belt("release", 4.5));
        m.apply(50, &belt("release", 4.5));
        let what: Vec<_> = m
            .actions
            .iter()
            .map(|a| (a.t_ns, a.what.as_str()))
            .collect();
        assert_eq!(
            what,
            vec![(20, "pretensioner_fire"), (40, "pretensioner_release")]
        );
        assert_eq!(m.limiter_at(25), Some(4.0));
        assert_eq!(m.limiter_at(35), Some(4.5));
        assert_eq!(
            m.limiter_at(5),
            Some(4.0),
            "before any level: the first one"
        );
    }

    #[test]
    fn airbag_fires_only_when_armed_and_only_once() {
        let mut m = Modules::default();
        m.apply(10, &bag(false, true, 6.0));
        assert!(!m.airbag_fired);
        assert_eq!(m.actions[0].what, "airbag_fire_ignored_disarmed");
        m.apply(20, &bag(true, false, 6.0));
        m.apply(30, &bag(true, true, 6.5));
        m.apply(40, &bag(true, true, 8.0));
        assert!(m.airbag_fired);
        let fire = m.action("airbag_fire").expect("fired");
        assert_eq!((fire.t_ns, fire.level_kn), (30, 6.5));
        assert_eq!(m.first_armed_ns, Some(20));
    }

    #[test]
    fn decodes_real_frames() {
        use bus::codec::*;
        let mut p = bus::E2eProtector::new();
        let f = p.seal(
            bus::AirbagStageCmd::encode(
                AirbagStageCmdArm::Armed,
                AirbagStageCmdFire::Fire,
                AirbagStageCmdCmdSource::Reference,
                AirbagStageCmdStage::Stage2,
                6.5,
                10.0,
            )
            .unwrap(),
        );
        let msg = bus::decode(f.id, f.payload()).expect("valid");
        match decode(&msg) {
            Decoded::Airbag {
                armed,
                fire,
                source,
                stage,
                force_level_kn,
                fire_time_ms,
            } => {
                assert!(armed && fire);
                assert_eq!(source, "reference");
                assert_eq!(stage, 2);
                assert_eq!(force_level_kn, 6.5);
                assert_eq!(fire_time_ms, 10.0);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn status_frames_carry_the_fault_flags_in_name_order() {
        use bus::codec::*;
        let mut p = bus::E2eProtector::new();
        // object input (bit 2) and overrun (bit 6), as the ECU encodes them.
        let f = p.seal(
            bus::EcuStatus::encode(
                EcuStatusEcuMode::ReferenceFallback,
                false,
                false,
                true,
                false,
                false,
                false,
                true,
                false,
                false,
                false,
                false,
                3,
                0x2ec7,
            )
            .unwrap(),
        );
        let msg = bus::decode(f.id, f.payload()).expect("valid");
        let Decoded::Status { mode, faults } = decode(&msg) else {
            panic!("not a status frame")
        };
        assert_eq!(mode, 2);
        assert_eq!(
            crate::status::ecu_fault_names(faults),
            ["object_input", "overrun"]
        );
        let mut m = Modules::default();
        m.apply(5, &Decoded::Status { mode, faults });
        m.apply(6, &Decoded::Status { mode, faults });
        m.apply(7, &Decoded::Status { mode, faults: 0 });
        assert_eq!(m.ecu_faults, [(5, faults), (7, 0)]);
    }
}
