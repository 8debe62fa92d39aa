//! Where each setting comes from. Four layers, each overriding the one before:
//!
//! 1. the defaults (`EcuConfig::default()`, shown in `ecu/ecu.toml`),
//! 2. the `--config` file,
//! 3. `$VCAN`, the CAN interface every bench tool reads (what `./vcan-setup.sh` exports), then
//!    `ECU_*` environment variables (`ECU_PERIOD_US=500`; `__` between table and key:
//!    `ECU_RT__SCHED_FIFO_PRIORITY=80`, `ECU_CYCLE__LUT=my.lut`),
//! 4. the command-line flags.
//!
//! figment merges them and keeps, for every value, the layer it came from: a range error, an
//! environment variable of the wrong type and `ecu --show-config` all name that origin
//! (`ecu.toml:12`, `environment variable ECU_RT__CPU`, `command line`, `defaults`). The file is
//! first checked on its own ([`EcuConfig::from_toml_str`]) because only that check knows
//! lines and columns; figment's own errors do not.

use std::path::{Path, PathBuf};

use figment::providers::{Env, Format, Serialized, Toml};
use figment::{Figment, Provider, Source};

use super::{ConfigError, EcuConfig};
use crate::runtime::cli::COMMAND_LINE;
use toml_location::line_of_key;

/// Prefix of the environment layer's variables.
pub const ENV_PREFIX: &str = "ECU_";
/// Separates a table from its key in an environment variable's name (`ECU_RT__CPU`).
const ENV_NESTING: &str = "__";

/// The merged layers of one resolution (what [`EcuConfig::resolve`] extracts from).
pub struct Layers {
    figment: Figment,
    /// The config file's path and text (for the line of a key).
    file: Option<(PathBuf, String)>,
}

impl Layers {
    /// Defaults ← `file` (read and checked strictly here) ← environment ← `command_line`.
    pub fn new(file: Option<&Path>, command_line: impl Provider) -> Result<Self, ConfigError> {
        let mut figment = Figment::from(Serialized::defaults(EcuConfig::default()));
        let file = match file {
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Read {
                    path: path.to_owned(),
                    cause,
                })?;
                EcuConfig::from_toml_str(&text, path)?;
                figment = figment.merge(Toml::file_exact(path));
                Some((path.to_owned(), text))
            }
            None => None,
        };
        if let Some(iface) = std::env::var("VCAN").ok().filter(|v| !v.is_empty()) {
            figment = figment.merge(VcanEnv(iface));
        }
        let figment = figment
            .merge(Env::prefixed(ENV_PREFIX).split(ENV_NESTING))
            .merge(command_line);
        Ok(Self { figment, file })
    }

    /// The merged configuration, range-checked; errors name the layer of the value.
    pub fn extract(&self) -> Result<EcuConfig, ConfigError> {
        let cfg: EcuConfig = self.figment.extract().map_err(|e| {
            // Only the environment can get here: the file passed its own check and the flags
            // are typed by clap. The first error is the one to fix.
            let e = e.into_iter().next().unwrap_or_else(|| "no value".into());
            // The path ends in the offending key (an unknown field's name included).
            let key = e.path.join(".");
            ConfigError::Invalid {
                origin: self.origin(&key),
                key,
                message: e.kind.to_string(),
            }
        })?;
        cfg.validate(&|key| self.origin(key))?;
        Ok(cfg)
    }

    /// Relative file paths resolved as the user meant them (the ECU started from
    /// another folder ran without its table and keys): a path from the `--config` file is
    /// relative to that file's folder (or the nearest folder above it that holds it); a default (`data/default.lut`, …) to the repository the
    /// ECU belongs to — the first folder holding it, walking up from the current directory,
    /// then from the executable's; a flag or environment value to the current directory, as
    /// typed.
    pub fn resolve_files(&self, cfg: &mut EcuConfig) {
        let file_dir = self
            .file
            .as_ref()
            .and_then(|(p, _)| p.parent().map(Path::to_path_buf));
        let c = &mut cfg.cycle;
        for (key, path) in [
            ("cycle.lut", &mut c.lut),
            ("cycle.reference", &mut c.reference),
            ("cycle.secoc_keys", &mut c.secoc_keys),
        ] {
            if path.is_absolute() {
                continue;
            }
            let metadata = self.figment.find_metadata(key);
            let from_file = metadata.is_some_and(|m| matches!(m.source, Some(Source::File(_))));
            let from_user = metadata
                .is_some_and(|m| m.name == COMMAND_LINE || m.name.contains("environment variable"));
            if from_file {
                if let Some(dir) = &file_dir {
                    // Beside the file, or the nearest folder above it that holds it
                    // (`ecu/ecu.toml`'s `data/default.lut` is the repository's).
                    *path = dir
                        .ancestors()
                        .map(|a| a.join(&*path))
                        .find(|p| p.exists())
                        .unwrap_or_else(|| dir.join(&*path));
                }
            } else if !from_user {
                if let Some(found) = host::find_upwards(path) {
                    *path = found;
                }
            }
        }
    }

    /// Where the value of the dotted `key` came from.
    pub fn origin(&self, key: &str) -> String {
        let Some(metadata) = self.figment.find_metadata(key) else {
            // A key no layer sets, e.g. an unknown one from the environment.
            return env_origin(key);
        };
        match &metadata.source {
            Some(Source::File(path)) => match &self.file {
                Some((_, text)) => origin_in_file(text, path, key),
                None => path.display().to_string(),
            },
            _ if metadata.name == COMMAND_LINE => COMMAND_LINE.to_owned(),
            _ if metadata.name == VCAN_ORIGIN => VCAN_ORIGIN.to_owned(),
            // figment names it "`ECU_` environment variable(s)".
            _ if metadata.name.contains("environment variable") => env_origin(key),
            _ => "defaults".to_owned(),
        }
    }

    /// The effective configuration as TOML, every value followed by its origin
    /// (`ecu --show-config`).
    pub fn show(&self, cfg: &EcuConfig) -> String {
        let text = match toml::to_string(cfg) {
            Ok(t) => t,
            Err(e) => return format!("# cannot print the configuration: {e}\n"),
        };
        let Ok(mut doc) = text.parse::<toml_edit::DocumentMut>() else {
            return text;
        };
        self.annotate(doc.as_table_mut(), "");
        let mut out = doc.to_string();
        // TOML has no null: an optional setting that is not set would simply be missing, so
        // the user would not learn it exists. serde_json keeps it (as null); each one becomes a
        // comment line at the top of its table.
        if let Ok(json) = serde_json::to_value(cfg) {
            let mut unset = Vec::new();
            unset_keys(&json, "", &mut unset);
            for (table, key) in unset.iter().rev() {
                let line = format!("# {key} = (not set)\n");
                match table.as_str() {
                    "" => out.insert_str(0, &line),
                    t => {
                        let header = format!("[{t}]\n");
                        if let Some(i) = out.find(&header) {
                            out.insert_str(i + header.len(), &line);
                        }
                    }
                }
            }
        }
        out
    }

    fn annotate(&self, table: &mut toml_edit::Table, prefix: &str) {
        for (key, item) in table.iter_mut() {
            let dotted = format!("{prefix}{}", key.get());
            match item {
                toml_edit::Item::Table(t) => self.annotate(t, &format!("{dotted}.")),
                toml_edit::Item::Value(v) => {
                    v.decor_mut()
                        .set_suffix(format!("  # {}", self.origin(&dotted)));
                }
                _ => {}
            }
        }
    }
}

/// The optional settings that are not set, as (table, key): the nulls of the JSON form.
fn unset_keys(v: &serde_json::Value, table: &str, out: &mut Vec<(String, String)>) {
    let Some(map) = v.as_object() else { return };
    for (key, value) in map {
        match value {
            serde_json::Value::Null => out.push((table.to_owned(), key.clone())),
            serde_json::Value::Object(_) => {
                let inner = if table.is_empty() {
                    key.clone()
                } else {
                    format!("{table}.{key}")
                };
                unset_keys(value, &inner, out);
            }
            _ => {}
        }
    }
}

/// The origin `$VCAN` shows as.
const VCAN_ORIGIN: &str = "environment variable VCAN";

/// `$VCAN` as the `can.interface` layer: the one name for the bench's interface that
/// `sensor-feeds`, `actuator-stubs` and the test tools read too.
struct VcanEnv(String);

impl Provider for VcanEnv {
    fn metadata(&self) -> figment::Metadata {
        figment::Metadata::named(VCAN_ORIGIN)
    }

    fn data(
        &self,
    ) -> Result<figment::value::Map<figment::Profile, figment::value::Dict>, figment::Error> {
        Serialized::default("can.interface", &self.0).data()
    }
}

/// `environment variable ECU_RT__CPU` for `rt.cpu`.
fn env_origin(key: &str) -> String {
    format!(
        "environment variable {ENV_PREFIX}{}",
        key.to_ascii_uppercase().replace('.', ENV_NESTING)
    )
}

/// `path:line` of the dotted `key` (from the span `toml_edit` keeps for it), or `path` when
/// the file does not set it.
pub(super) fn origin_in_file(text: &str, path: &Path, key: &str) -> String {
    match line_of_key(text, key) {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}
