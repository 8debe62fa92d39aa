//! Configuration: a TOML file (`--config FILE`) overridden by CLI flags.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand};
use serde::{Deserialize, Serialize};

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
    /// Characteristic diagram (LUT) file (`--lut`). Missing/corrupt → DEGRADED mode with the
    /// reference restraint; the ECU still starts.
    pub lut: PathBuf,
    /// Reference-restraint file (`--reference`). Missing/corrupt → the copy built into the
    /// binary (same file at build time), with a warning.
    pub reference: PathBuf,
    /// SecOC key file (`--secoc-keys`, format in `bus::secoc::SecOcKeys`). Missing/corrupt →
    /// the ECU still starts and still sends its (E2E-protected) commands, but without
    /// authenticator frames, and reports `FaultConfig` in `EcuStatus`: an unauthenticated
    /// command that authenticated actuators ignore is still better than refusing to protect,
    /// and the fault bit tells the bench why the actuators are not acting.
    pub secoc_keys: PathBuf,
    /// The decision thresholds (same table; unknown keys are rejected by the core's struct).
    #[serde(flatten)]
    pub decision: restraint::CycleConfig,
}

mod cycle_section {
    //! Deserialises `[cycle]` without `#[serde(flatten)]` (which would lose toml's line
    //! numbers and switch off `deny_unknown_fields`): a map access that hands the three file
    //! keys to the shell and every other key, with its span, to the core's derived impl.

    use std::path::PathBuf;

    use serde::de::value::MapAccessDeserializer;
    use serde::de::{DeserializeSeed, Deserializer, IntoDeserializer, MapAccess, Visitor};
    use serde::Deserialize;

    use super::CycleSection;

    /// A key of `[cycle]`: one of the core's fields, or a file key (with the unused seed).
    enum Key<F, K> {
        Field(F),
        File(usize, K),
    }

    const FILE_KEYS: [&str; 3] = ["lut", "reference", "secoc_keys"];

    struct KeySeed<K>(K);

    impl<'de, K: DeserializeSeed<'de>> DeserializeSeed<'de> for KeySeed<K> {
        type Value = Key<K::Value, K>;
        fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            let key = String::deserialize(d)?;
            match FILE_KEYS.iter().position(|k| *k == key) {
                Some(i) => Ok(Key::File(i, self.0)),
                // Inside toml's key deserialisation: an unknown key gets the key's span. The
                // core's "expected one of" list does not know the file keys: they are added.
                None => self
                    .0
                    .deserialize(key.as_str().into_deserializer())
                    .map(Key::Field)
                    .map_err(|e: D::Error| {
                        serde::de::Error::custom(format_args!(
                            "{e}, or one of the file keys `lut`, `reference`, `secoc_keys`"
                        ))
                    }),
            }
        }
    }

    struct Split<'f, A> {
        inner: A,
        files: &'f mut [Option<PathBuf>; 3],
    }

    impl<'de, A: MapAccess<'de>> MapAccess<'de> for Split<'_, A> {
        type Error = A::Error;
        fn next_key_seed<K: DeserializeSeed<'de>>(
            &mut self,
            seed: K,
        ) -> Result<Option<K::Value>, A::Error> {
            let mut seed = seed;
            loop {
                match self.inner.next_key_seed(KeySeed(seed))? {
                    None => return Ok(None),
                    Some(Key::Field(f)) => return Ok(Some(f)),
                    Some(Key::File(i, s)) => {
                        let path: PathBuf = self.inner.next_value()?;
                        if let Some(slot) = self.files.get_mut(i) {
                            *slot = Some(path);
                        }
                        seed = s;
                    }
                }
            }
        }
        fn next_value_seed<V: DeserializeSeed<'de>>(
            &mut self,
            seed: V,
        ) -> Result<V::Value, A::Error> {
            self.inner.next_value_seed(seed)
        }
    }

    struct SectionVisitor;

    impl<'de> Visitor<'de> for SectionVisitor {
        type Value = CycleSection;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("the [cycle] table")
        }
        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<CycleSection, A::Error> {
            let mut files = [None, None, None];
            let decision =
                restraint::CycleConfig::deserialize(MapAccessDeserializer::new(Split {
                    inner: map,
                    files: &mut files,
                }))?;
            let [lut, reference, secoc_keys] = files;
            let d = CycleSection::default();
            Ok(CycleSection {
                lut: lut.unwrap_or(d.lut),
                reference: reference.unwrap_or(d.reference),
                secoc_keys: secoc_keys.unwrap_or(d.secoc_keys),
                decision,
            })
        }
    }

    impl<'de> Deserialize<'de> for CycleSection {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            d.deserialize_map(SectionVisitor)
        }
    }
}

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
    #[error("{path}: cannot read config file: {source}")]
    Read {
        /// File path.
        path: PathBuf,
        /// OS error.
        source: std::io::Error,
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
    /// A value is out of range.
    #[error("{origin}: invalid `{key}`: {message}")]
    Invalid {
        /// `file:line` of the key, or `command line`.
        origin: String,
        /// Dotted key, e.g. `rt.sched_fifo_priority`.
        key: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// 1-based (line, column) of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

impl EcuConfig {
    /// Parses TOML text; errors name `path:line:column`.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let cfg: Self = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((1, 1), |s| line_col(text, s.start));
            ConfigError::Parse {
                path: path.to_owned(),
                line,
                column,
                message: e.message().trim().to_owned(),
            }
        })?;
        cfg.validate(&|key: &str| origin_in_file(text, path, key))?;
        Ok(cfg)
    }

    /// Reads and parses a TOML file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::from_toml_str(&text, path)
    }

    /// Range checks. `origin(key)` says where a key came from (for the message).
    pub fn validate(&self, origin: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
        let invalid = |key: &'static str, message: String| ConfigError::Invalid {
            origin: origin(key),
            key,
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
            return Err(invalid("cycle", e.to_string()));
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

    /// Applies CLI overrides (a flag given on the command line wins over the file).
    pub fn apply_cli(&mut self, a: &RunArgs) {
        if let Some(v) = a.period_us {
            self.period_us = v;
        }
        if let Some(v) = a.cycles {
            self.cycles = Some(v);
        }
        if let Some(v) = &a.report_json {
            self.report_json = Some(v.clone());
        }
        if let Some(v) = a.sched_fifo {
            self.rt.sched_fifo_priority = Some(v);
        }
        if a.mlockall {
            self.rt.mlockall = true;
        }
        if a.no_mlockall {
            self.rt.mlockall = false;
        }
        if let Some(v) = a.cpu {
            self.rt.cpu = Some(v);
        }
        if a.pm_qos {
            self.rt.pm_qos = true;
        }
        if a.no_pm_qos {
            self.rt.pm_qos = false;
        }
        if let Some(v) = a.prefault_stack_kib {
            self.rt.prefault_stack_kib = v;
        }
        if let Some(v) = &a.lut {
            self.cycle.lut = v.clone();
        }
        if let Some(v) = &a.reference {
            self.cycle.reference = v.clone();
        }
        if let Some(v) = &a.secoc_keys {
            self.cycle.secoc_keys = v.clone();
        }
        if a.no_can {
            self.can.enabled = false;
        }
        if let Some(v) = &a.can_interface {
            self.can.interface = v.clone();
        }
        if let Some(v) = &a.service_prefix {
            self.ipc.service_prefix = v.clone();
        }
        if let Some(v) = &a.node_name {
            self.ipc.node_name = v.clone();
        }
    }

    /// File (optional) + CLI, validated. CLI values are reported as `command line`.
    pub fn resolve(a: &RunArgs) -> Result<Self, ConfigError> {
        let (mut cfg, text) = match &a.config {
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
                    path: path.clone(),
                    source,
                })?;
                (
                    Self::from_toml_str(&text, path)?,
                    Some((text, path.clone())),
                )
            }
            None => (Self::default(), None),
        };
        cfg.apply_cli(a);
        cfg.validate(&|key: &str| {
            if a.overrides(key) {
                "command line".to_owned()
            } else if let Some((text, path)) = &text {
                origin_in_file(text, path, key)
            } else {
                "defaults".to_owned()
            }
        })?;
        Ok(cfg)
    }
}

/// `path:line` of the dotted `key` (from the span `toml_edit` keeps for it), or `path` when
/// the file does not set it.
fn origin_in_file(text: &str, path: &Path, key: &str) -> String {
    let line = toml_edit::ImDocument::parse(text).ok().and_then(|doc| {
        let mut table: &dyn toml_edit::TableLike = doc.as_table();
        let mut parts = key.split('.').peekable();
        while let Some(part) = parts.next() {
            let (k, item) = table.get_key_value(part)?;
            if parts.peek().is_none() {
                return k.span().or_else(|| item.span());
            }
            table = item.as_table_like()?;
        }
        None
    });
    match line {
        Some(span) => format!("{}:{}", path.display(), line_col(text, span.start).0),
        None => path.display().to_string(),
    }
}

/// `ecu` command line.
#[derive(Debug, Parser)]
#[command(
    name = "ecu",
    version,
    about = "Fixed-rate adaptive restraint ECU (real-time loop, iceoryx2 + CAN I/O)",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// Subcommand (default: run the ECU).
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Options of the ECU run.
    #[command(flatten)]
    pub run: RunArgs,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Show the ECU diagnostics (mode, settings, timing) live; Ctrl-C to exit.
    Monitor(MonitorArgs),
}

/// `ecu monitor` options.
#[derive(Debug, Args, Clone)]
pub struct MonitorArgs {
    /// Config file (only `ipc.service_prefix` is used).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// iceoryx2 service-name prefix.
    #[arg(long, value_name = "PREFIX")]
    pub service_prefix: Option<String>,
    /// Display refresh rate.
    #[arg(long, default_value_t = 10.0, value_name = "HZ")]
    pub rate_hz: f64,
    /// Exit after this many refreshes (default: until Ctrl-C).
    #[arg(long, value_name = "N")]
    pub count: Option<u64>,
    /// One line per refresh instead of an in-place refreshing line (for logs/pipes).
    #[arg(long)]
    pub lines: bool,
}

/// `ecu` run options; each overrides the config file.
#[derive(Debug, Args, Clone, Default)]
pub struct RunArgs {
    /// TOML config file (see ecu/ecu.toml); flags override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Cycle period in µs (default 1000 = 1 kHz).
    #[arg(long, value_name = "US")]
    pub period_us: Option<u64>,
    /// Stop after N cycles and print the report (default: until SIGINT/SIGTERM).
    #[arg(long, value_name = "N")]
    pub cycles: Option<u64>,
    /// Also write the timing report as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub report_json: Option<PathBuf>,
    /// Request SCHED_FIFO at this priority (1..=99); degrades with a message if denied.
    #[arg(long, value_name = "PRIO")]
    pub sched_fifo: Option<u8>,
    /// Request mlockall(MCL_CURRENT|MCL_FUTURE).
    #[arg(long, conflicts_with = "no_mlockall")]
    pub mlockall: bool,
    /// Do not lock memory (overrides the file).
    #[arg(long)]
    pub no_mlockall: bool,
    /// Pin the process to this CPU.
    #[arg(long, value_name = "CPU")]
    pub cpu: Option<usize>,
    /// Hold /dev/cpu_dma_latency at 0 while running.
    #[arg(long, conflicts_with = "no_pm_qos")]
    pub pm_qos: bool,
    /// Do not touch PM-QoS (overrides the file).
    #[arg(long)]
    pub no_pm_qos: bool,
    /// Stack to pre-fault before the loop, KiB.
    #[arg(long, value_name = "KIB")]
    pub prefault_stack_kib: Option<usize>,
    /// Switch the CAN side off (e.g. no SocketCAN on this host); the report says so.
    #[arg(long)]
    pub no_can: bool,
    /// SocketCAN interface (default vcan0).
    #[arg(long, value_name = "IF")]
    pub can_interface: Option<String>,
    /// iceoryx2 service-name prefix.
    #[arg(long, value_name = "PREFIX")]
    pub service_prefix: Option<String>,
    /// iceoryx2 node name.
    #[arg(long, value_name = "NAME")]
    pub node_name: Option<String>,
    /// Do not print the start-up summary.
    #[arg(long)]
    pub quiet: bool,
    /// Characteristic diagram (default data/default.lut). Missing or corrupt: the ECU says
    /// why and runs DEGRADED on the reference restraint.
    #[arg(long, value_name = "FILE")]
    pub lut: Option<PathBuf>,
    /// Reference-restraint file (default data/reference-restraint.toml; missing or corrupt:
    /// the copy built into the binary).
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// SecOC key file (default data/secoc-keys.example.toml; missing or corrupt: the ECU
    /// starts without authenticator frames and reports FaultConfig).
    #[arg(long, value_name = "FILE")]
    pub secoc_keys: Option<PathBuf>,
}

impl RunArgs {
    /// Whether the CLI sets the config key `key`.
    fn overrides(&self, key: &str) -> bool {
        match key {
            "period_us" => self.period_us.is_some(),
            "rt.sched_fifo_priority" => self.sched_fifo.is_some(),
            "rt.prefault_stack_kib" => self.prefault_stack_kib.is_some(),
            "ipc.node_name" => self.node_name.is_some(),
            "ipc.service_prefix" => self.service_prefix.is_some(),
            "can.interface" => self.can_interface.is_some(),
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // The prediction is solved in closed form since issue 15: the old step key is an
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
    fn missing_file_is_a_clear_error() {
        let e = EcuConfig::load(Path::new("/nonexistent/ecu.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("/nonexistent/ecu.toml: cannot read config file"),
            "{e}"
        );
    }

    #[test]
    fn monitor_subcommand_parses() {
        let cli = Cli::try_parse_from(["ecu", "monitor", "--count", "3"]).unwrap();
        assert!(matches!(
            cli.command,
            Some(Command::Monitor(MonitorArgs { count: Some(3), .. }))
        ));
    }
}
