//! The `ecu` command line (clap), and its flags as the top layer of the configuration.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use figment::value::{Dict, Map, Value};
use figment::{Metadata, Profile, Provider};

/// Name of the command-line layer (the origin in error messages and `--show-config`).
pub const COMMAND_LINE: &str = "command line";

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
    /// TOML config file (see ecu/ecu.toml); ECU_* environment variables and flags override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Print the effective configuration, each value with the layer it came from (default,
    /// file:line, environment variable or command line), and exit.
    #[arg(long)]
    pub show_config: bool,
    /// Cycle period in µs (default 1000 = 1 kHz).
    #[arg(long, value_name = "US")]
    pub period_us: Option<u64>,
    /// Stop after N cycles and print the report (default: until SIGINT/SIGTERM).
    #[arg(long, value_name = "N")]
    pub cycles: Option<u64>,
    /// Also write the timing report as JSON to FILE (`-`: stdout, after the text report).
    #[arg(long = "json", alias = "report-json", value_name = "FILE")]
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
    /// SocketCAN interface (default vcan0); `--can`, as in every bench tool.
    #[arg(long, alias = "can-interface", value_name = "IF")]
    pub can: Option<String>,
    /// iceoryx2 service-name prefix.
    #[arg(long, value_name = "PREFIX")]
    pub service_prefix: Option<String>,
    /// iceoryx2 node name.
    #[arg(long, value_name = "NAME")]
    pub node_name: Option<String>,
    /// Do not print the start-up summary.
    #[arg(long)]
    pub quiet: bool,
    /// Characteristic diagram (default: the repository's data/default.lut, found from any
    /// folder). Not found: the ECU does not start (unless --no-lut); found but corrupt: it says
    /// why and runs DEGRADED on the reference restraint.
    #[arg(long, value_name = "FILE", conflicts_with = "no_lut")]
    pub lut: Option<PathBuf>,
    /// Run without a characteristic diagram: DEGRADED on the reference restraint, on purpose.
    #[arg(long)]
    pub no_lut: bool,
    /// Reference-restraint file (default: the repository's data/reference-restraint.toml;
    /// missing or corrupt: the copy built into the binary).
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// SecOC key file (default: the repository's data/secoc-keys.example.toml). Missing or
    /// unusable: the ECU does not start — its fire commands would go out unauthenticated —
    /// unless --no-secoc.
    #[arg(long, value_name = "FILE", conflicts_with = "no_secoc")]
    pub secoc_keys: Option<PathBuf>,
    /// Send commands without SecOC authenticators, on purpose (authenticated actuators ignore
    /// them; EcuStatus.FaultConfig is set and the start-up line says so).
    #[arg(long)]
    pub no_secoc: bool,
}

impl RunArgs {
    /// The flags given, as (dotted config key, value); absent flags set nothing.
    fn settings(&self) -> Vec<(&'static str, Option<Value>)> {
        fn v<T: serde::Serialize>(x: Option<T>) -> Option<Value> {
            x.and_then(|x| Value::serialize(x).ok())
        }
        // `--x` / `--no-x` pairs (clap makes them exclusive): the one given wins over the file.
        let pair = |on: bool, off: bool| v((on || off).then_some(on));
        vec![
            ("period_us", v(self.period_us)),
            ("cycles", v(self.cycles)),
            ("report_json", v(self.report_json.as_ref())),
            ("rt.sched_fifo_priority", v(self.sched_fifo)),
            ("rt.mlockall", pair(self.mlockall, self.no_mlockall)),
            ("rt.cpu", v(self.cpu)),
            ("rt.pm_qos", pair(self.pm_qos, self.no_pm_qos)),
            ("rt.prefault_stack_kib", v(self.prefault_stack_kib)),
            ("cycle.lut", v(self.lut.as_ref())),
            ("cycle.reference", v(self.reference.as_ref())),
            ("cycle.secoc_keys", v(self.secoc_keys.as_ref())),
            ("can.enabled", v(self.no_can.then_some(false))),
            ("can.interface", v(self.can.as_ref())),
            ("ipc.service_prefix", v(self.service_prefix.as_ref())),
            ("ipc.node_name", v(self.node_name.as_ref())),
        ]
    }
}

impl Provider for RunArgs {
    fn metadata(&self) -> Metadata {
        Metadata::named(COMMAND_LINE)
    }
    fn data(&self) -> Result<Map<Profile, Dict>, figment::Error> {
        Ok(Profile::Default.collect(nested(self.settings())))
    }
}

impl Provider for MonitorArgs {
    fn metadata(&self) -> Metadata {
        Metadata::named(COMMAND_LINE)
    }
    fn data(&self) -> Result<Map<Profile, Dict>, figment::Error> {
        let prefix = self
            .service_prefix
            .as_ref()
            .map(|p| Value::from(p.as_str()));
        Ok(Profile::Default.collect(nested(vec![("ipc.service_prefix", prefix)])))
    }
}

/// `[("rt.cpu", Some(1))]` → `{ rt: { cpu: 1 } }`: the layer figment merges.
fn nested(settings: Vec<(&'static str, Option<Value>)>) -> Dict {
    fn insert(dict: &mut Dict, key: &str, value: Value) {
        match key.split_once('.') {
            None => {
                dict.insert(key.to_owned(), value);
            }
            Some((table, rest)) => {
                let entry = dict
                    .entry(table.to_owned())
                    .or_insert_with(|| Value::from(Dict::new()));
                if let Value::Dict(_, inner) = entry {
                    insert(inner, rest, value);
                }
            }
        }
    }
    let mut dict = Dict::new();
    for (key, value) in settings {
        if let Some(value) = value {
            insert(&mut dict, key, value);
        }
    }
    dict
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monitor_subcommand_parses() {
        let cli = Cli::try_parse_from(["ecu", "monitor", "--count", "3"]).unwrap();
        assert!(matches!(
            cli.command,
            Some(Command::Monitor(MonitorArgs { count: Some(3), .. }))
        ));
    }

    #[test]
    fn only_the_flags_given_are_a_layer_and_dotted_keys_nest() {
        let cli = Cli::try_parse_from(["ecu", "--cpu", "1", "--no-mlockall", "--no-can"]).unwrap();
        let dict = cli.run.data().unwrap().remove(&Profile::Default).unwrap();
        let rt = dict["rt"].as_dict().unwrap();
        assert_eq!(rt["cpu"].to_u128(), Some(1));
        assert_eq!(rt["mlockall"].to_bool(), Some(false));
        assert_eq!(rt.len(), 2, "{rt:?}");
        assert_eq!(
            dict["can"].as_dict().unwrap()["enabled"].to_bool(),
            Some(false)
        );
        assert_eq!(dict.len(), 2, "{dict:?}");
        let none = Cli::try_parse_from(["ecu"]).unwrap();
        assert!(none.run.data().unwrap()[&Profile::Default].is_empty());
    }
}
