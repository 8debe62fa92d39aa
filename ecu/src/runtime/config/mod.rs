//! The ECU's configuration: the schema (this file, one struct per table of `ecu/ecu.toml`), the
//! strict check of a config file with `file:line:column` errors, range checks, and the layers
//! it is merged from ([`Layers`]: defaults ← file ← `ECU_*` environment ← command line).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml_location::{field_at, line_col};

use super::cli::RunArgs;

/// Shortest supported cycle period. Below this the loop is dominated by syscall cost.
pub const MIN_PERIOD_US: u64 = 50;
/// Longest supported cycle period (1 s).
pub const MAX_PERIOD_US: u64 = 1_000_000;

/// The complete ECU runtime configuration (file schema = this struct; see `ecu/ecu.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EcuConfig {
    /// Cycle period, µs (default 1000 = 1 kHz).
    pub period_us: u64,
    /// Stop after this many cycles (absent: run until SIGINT/SIGTERM).
    pub cycles: Option<u64>,
    /// Write the JSON timing report here on exit.
    pub report_json: Option<PathBuf>,
    /// Real-time settings.
    pub rt: RtConfig,
    /// iceoryx2 settings.
    pub ipc: IpcConfig,
    /// CAN settings.
    pub can: CanConfig,
    /// Restraint decision thresholds and the files the shell loads for the cycle.
    pub cycle: CycleSection,
}

/// `[cycle]`: the files the shell loads for the restraint core, and the core's decision
/// thresholds ([`restraint::CycleConfig`], same table: every key documented there). Read by
/// [`cycle_section`]: the file keys are taken out, everything else goes to the core's struct,
/// which rejects unknown keys and reports wrong types at their line as any other table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleSection {
    /// Characteristic diagram (LUT) file (`--lut`). Relative paths: from the config file,
    /// beside it; the default, in the repository the ECU belongs to (found from any folder;
    /// `Layers::resolve_files`). Not found → the ECU does not start unless `--no-lut` (a
    /// set-up mistake); found but corrupt → DEGRADED mode with the reference restraint, the
    /// ECU still starts (a fault it must survive: never "no protection").
    pub lut: PathBuf,
    /// Reference-restraint file (`--reference`). Missing/corrupt → the copy built into the
    /// binary (same file at build time), with a warning.
    pub reference: PathBuf,
    /// SecOC key file (`--secoc-keys`, format in `bus::secoc::SecOcKeys`). Missing/corrupt →
    /// the ECU does not start (fail closed: its fire commands would go out without
    /// authenticators), unless `--no-secoc` asks for exactly that; then `EcuStatus` reports
    /// `FaultConfig` and the start-up line says why.
    pub secoc_keys: PathBuf,
    /// The decision thresholds (same table; unknown keys are rejected by the core's struct).
    #[serde(flatten)]
    pub decision: restraint::CycleConfig,
}

mod cycle_section;
mod layers;

pub use layers::{Layers, ENV_PREFIX};

impl Default for CycleSection {
    fn default() -> Self {
        Self {
            lut: PathBuf::from("data/default.lut"),
            reference: PathBuf::from("data/reference-restraint.toml"),
            secoc_keys: PathBuf::from("data/secoc-keys.example.toml"),
            decision: restraint::CycleConfig::default(),
        }
    }
}

/// Real-time settings; each is optional and degrades with a message when not permitted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RtConfig {
    /// SCHED_FIFO priority 1..=99 (absent: normal scheduling).
    pub sched_fifo_priority: Option<u8>,
    /// mlockall(MCL_CURRENT | MCL_FUTURE).
    pub mlockall: bool,
    /// Pin the process to this CPU (absent: no pinning).
    pub cpu: Option<usize>,
    /// Hold /dev/cpu_dma_latency at 0 (no deep C-states) while running.
    pub pm_qos: bool,
    /// Stack to pre-fault before the loop, KiB (0 = none).
    pub prefault_stack_kib: usize,
}

/// iceoryx2 settings (service names themselves come from the `ipc` crate).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IpcConfig {
    /// Service-name prefix (`ipc::DEFAULT_SERVICE_PREFIX` by default).
    pub service_prefix: String,
    /// iceoryx2 node name of the ECU.
    pub node_name: String,
}

/// CAN settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CanConfig {
    /// Use the CAN side at all (`--no-can` sets false).
    pub enabled: bool,
    /// SocketCAN interface name.
    pub interface: String,
}

impl Default for EcuConfig {
    fn default() -> Self {
        Self {
            period_us: 1_000,
            cycles: None,
            report_json: None,
            rt: RtConfig::default(),
            ipc: IpcConfig::default(),
            can: CanConfig::default(),
            cycle: CycleSection::default(),
        }
    }
}

impl Default for RtConfig {
    fn default() -> Self {
        Self {
            sched_fifo_priority: None,
            mlockall: false,
            cpu: None,
            pm_qos: false,
            prefault_stack_kib: 256,
        }
    }
}

impl Default for IpcConfig {
    fn default() -> Self {
        Self {
            service_prefix: ipc::DEFAULT_SERVICE_PREFIX.to_owned(),
            node_name: "restraint-ecu".to_owned(),
        }
    }
}

impl Default for CanConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            interface: "vcan0".to_owned(),
        }
    }
}

/// A configuration error, with `file:line:column` when it comes from a file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: cannot read config file: {cause}")]
    Read {
        /// File path.
        path: PathBuf,
        /// OS error (in the message once: not a `source`, which error chains print again).
        cause: std::io::Error,
    },
    /// TOML syntax or schema error.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// File path.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A value is out of range, or (from the environment) of the wrong type or unknown.
    #[error("{origin}: invalid `{key}`: {message}")]
    Invalid {
        /// Where the value came from: `file:line`, `environment variable ECU_…`,
        /// `command line` or `defaults`.
        origin: String,
        /// Dotted key, e.g. `rt.sched_fifo_priority`.
        key: String,
        /// What is wrong.
        message: String,
    },
}

impl EcuConfig {
    /// Parses TOML text; errors name `path:line:column`.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let cfg: Self = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((1, 1), |s| line_col(text, s.start));
            // A type error names its value, not its key: say the key too (unknown and missing
            // keys already name theirs).
            let message = e.message().trim();
            let message = match e.span().and_then(|s| field_at(text, s.start)) {
                Some(key)
                    if !message
                        .contains(&format!("`{}`", key.rsplit('.').next().unwrap_or(&key))) =>
                {
                    format!("field `{key}`: {message}")
                }
                _ => message.to_owned(),
            };
            ConfigError::Parse {
                path: path.to_owned(),
                line,
                column,
                message,
            }
        })?;
        cfg.validate(&|key: &str| layers::origin_in_file(text, path, key))?;
        Ok(cfg)
    }

    /// Reads and parses a TOML file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Read {
            path: path.to_owned(),
            cause,
        })?;
        Self::from_toml_str(&text, path)
    }

    /// Defaults ← `--config` file ← `ECU_*` environment ← flags, range-checked (see [`Layers`]).
    pub fn resolve(a: &RunArgs) -> Result<Self, ConfigError> {
        Layers::new(a.config.as_deref(), a.clone())?.extract()
    }

    /// Range checks. `origin(key)` says where a key came from (for the message).
    pub fn validate(&self, origin: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
        let invalid = |key: &str, message: String| ConfigError::Invalid {
            origin: origin(key),
            key: key.to_owned(),
            message,
        };
        if !(MIN_PERIOD_US..=MAX_PERIOD_US).contains(&self.period_us) {
            return Err(invalid(
                "period_us",
                format!(
                    "{} µs is outside {MIN_PERIOD_US}..={MAX_PERIOD_US}",
                    self.period_us
                ),
            ));
        }
        if let Some(p) = self.rt.sched_fifo_priority {
            if !(1..=99).contains(&p) {
                return Err(invalid(
                    "rt.sched_fifo_priority",
                    format!("{p} is outside the SCHED_FIFO range 1..=99"),
                ));
            }
        }
        if self.rt.prefault_stack_kib > 4096 {
            return Err(invalid(
                "rt.prefault_stack_kib",
                format!(
                    "{} KiB exceeds 4096 KiB (the main thread stack is typically 8 MiB)",
                    self.rt.prefault_stack_kib
                ),
            ));
        }
        if let Err(e) = self.cycle.decision.validate() {
            return Err(invalid(&format!("cycle.{}", e.key), e.to_string()));
        }
        if self.ipc.node_name.is_empty() {
            return Err(invalid("ipc.node_name", "must not be empty".into()));
        }
        if self.ipc.service_prefix.is_empty() {
            return Err(invalid("ipc.service_prefix", "must not be empty".into()));
        }
        if self.can.enabled && self.can.interface.is_empty() {
            return Err(invalid("can.interface", "must not be empty".into()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::cli::Cli;
    use clap::Parser;

    fn p() -> PathBuf {
        PathBuf::from("ecu.toml")
    }

    #[test]
    fn empty_file_gives_defaults() {
        assert_eq!(
            EcuConfig::from_toml_str("", &p()).unwrap(),
            EcuConfig::default()
        );
        assert_eq!(EcuConfig::default().period_us, 1_000);
    }

    #[test]
    fn shipped_example_parses() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("ecu.toml");
        let cfg = EcuConfig::load(&path).unwrap();
        assert_eq!(cfg.period_us, 1_000);
        assert_eq!(cfg.can.interface, "vcan0");
        // The file shows the defaults: the core's thresholds, its track filter included.
        assert_eq!(cfg.cycle.decision, restraint::CycleConfig::default());
    }

    #[test]
    fn an_unknown_cycle_key_lists_the_file_keys_too() {
        let e = EcuConfig::from_toml_str("[cycle]\nlut_file = \"x.lut\"\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("lut_file"), "{e}");
        assert!(
            e.contains("`secoc_keys`") && e.contains("confirm_samples"),
            "{e}"
        );
        assert!(e.contains(":2:"), "the key's line: {e}");
    }

    #[test]
    fn removed_prediction_step_is_rejected_and_track_keys_are_read() {
        // The prediction is solved in closed form: the old step key is an
        // error that names it, not silently ignored.
        let e = EcuConfig::from_toml_str("[cycle]\nprediction_step_ms = 0.5\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("prediction_step_ms"), "{e}");
        let text = "[cycle]\nconfirm_samples = 4\n[cycle.track]\ngate_chi2 = 11.34\n";
        let cfg = EcuConfig::from_toml_str(text, &p()).unwrap();
        assert_eq!(cfg.cycle.decision.track.gate_chi2, 11.34);
        assert_eq!(cfg.cycle.decision.confirm_samples, 4);
        let e = EcuConfig::from_toml_str("[cycle.track]\ngate_chi2 = 0.5\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("track.gate_chi2"), "{e}");
    }

    #[test]
    fn syntax_error_names_file_line_and_column() {
        let text = "period_us = 500\n[rt]\nmlockall = yes\n";
        let e = EcuConfig::from_toml_str(text, &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:3:12:"), "{e}");
    }

    #[test]
    fn unknown_key_is_rejected_with_line() {
        let text = "period_us = 500\n\n[rt]\nmlock_all = true\n";
        let e = EcuConfig::from_toml_str(text, &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:4:"), "{e}");
        assert!(e.contains("mlock_all"), "{e}");
    }

    #[test]
    fn cycle_table_holds_the_shell_files_and_the_core_thresholds() {
        let text = "[cycle]\nlut = \"a.lut\"\nconfirm_decel_g = 5.0\nsecoc_keys = \"k.toml\"\n";
        let cfg = EcuConfig::from_toml_str(text, &p()).unwrap();
        assert_eq!(cfg.cycle.lut, PathBuf::from("a.lut"));
        assert_eq!(cfg.cycle.secoc_keys, PathBuf::from("k.toml"));
        assert_eq!(cfg.cycle.reference, CycleSection::default().reference);
        assert_eq!(cfg.cycle.decision.confirm_decel_g, 5.0);
        // Unknown keys and wrong types inside [cycle] name their line and column.
        let e = EcuConfig::from_toml_str("[cycle]\nlut = \"a\"\nconfirm_decel_gg = 4\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:3:1:"), "{e}");
        assert!(e.contains("confirm_decel_gg"), "{e}");
        let e = EcuConfig::from_toml_str("[cycle]\nconfirm_decel_g = \"x\"\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:2:19:"), "{e}");
    }

    #[test]
    fn wrong_type_is_rejected_with_line() {
        let e = EcuConfig::from_toml_str("\nperiod_us = \"fast\"\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:2:"), "{e}");
    }

    #[test]
    fn out_of_range_value_names_key_and_line() {
        let text = "period_us = 1000\n[rt]\nmlockall = true\nsched_fifo_priority = 0\n";
        let e = EcuConfig::from_toml_str(text, &p())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "ecu.toml:4: invalid `rt.sched_fifo_priority`: 0 is outside the SCHED_FIFO range 1..=99"
        );
        let e = EcuConfig::from_toml_str("period_us = 10\n", &p())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("ecu.toml:1: invalid `period_us`"), "{e}");
    }

    #[test]
    fn cli_overrides_file() {
        let dir = std::env::temp_dir().join(format!("ecu-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.toml");
        std::fs::write(
            &path,
            "period_us = 2000\n[rt]\nmlockall = true\npm_qos = true\n[can]\nenabled = true\n",
        )
        .unwrap();
        let cli = Cli::try_parse_from([
            "ecu",
            "--config",
            path.to_str().unwrap(),
            "--period-us",
            "500",
            "--no-mlockall",
            "--no-can",
        ])
        .unwrap();
        let cfg = EcuConfig::resolve(&cli.run).unwrap();
        assert_eq!(cfg.period_us, 500);
        assert!(!cfg.rt.mlockall);
        assert!(cfg.rt.pm_qos, "file value kept when no flag given");
        assert!(!cfg.can.enabled);

        let cli = Cli::try_parse_from([
            "ecu",
            "--config",
            path.to_str().unwrap(),
            "--period-us",
            "5",
        ])
        .unwrap();
        let e = EcuConfig::resolve(&cli.run).unwrap_err().to_string();
        assert!(e.starts_with("command line: invalid `period_us`"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn every_value_names_its_layer() {
        let dir = std::env::temp_dir().join(format!("ecu-layers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.toml");
        std::fs::write(
            &path,
            "period_us = 2000\n\n[cycle.track]\ngate_chi2 = 20.0\n",
        )
        .unwrap();
        let cli =
            Cli::try_parse_from(["ecu", "--config", path.to_str().unwrap(), "--cpu", "1"]).unwrap();
        let layers = Layers::new(cli.run.config.as_deref(), cli.run.clone()).unwrap();
        let cfg = layers.extract().unwrap();
        let file = path.display().to_string();
        assert_eq!(layers.origin("period_us"), format!("{file}:1"));
        assert_eq!(layers.origin("cycle.track.gate_chi2"), format!("{file}:4"));
        assert_eq!(layers.origin("rt.cpu"), "command line");
        assert_eq!(layers.origin("rt.mlockall"), "defaults");
        let shown = layers.show(&cfg);
        for line in [
            format!("period_us = 2000  # {file}:1"),
            format!("gate_chi2 = 20.0  # {file}:4"),
            "cpu = 1  # command line".to_owned(),
            "mlockall = false  # defaults".to_owned(),
        ] {
            assert!(shown.lines().any(|l| l == line), "{line} not in\n{shown}");
        }
        // What --show-config prints reads back as the same configuration.
        assert_eq!(EcuConfig::from_toml_str(&shown, &p()).unwrap(), cfg);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn missing_file_is_a_clear_error() {
        let e = EcuConfig::load(Path::new("/nonexistent/ecu.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("/nonexistent/ecu.toml: cannot read config file"),
            "{e}"
        );
    }
}
