//! Where `lut` finds the repository's files when a path is relative: the tools run from any
//! folder of the checkout (a study from `docs/`, a plot from `lut/`), as the ECU does.

use std::path::{Path, PathBuf};

/// The value parser of every input file argument: a relative path that does not exist from
/// the current folder is looked up in the enclosing folders, then beside the executable
/// (`host::files::find_upwards`), so `data/default.lut` — a default or typed — names the
/// repository's table from any folder in it. A path found nowhere is kept as given, so the
/// error names it as the user wrote it.
pub fn input_file(s: &str) -> Result<PathBuf, std::convert::Infallible> {
    Ok(resolve(Path::new(s)))
}

/// [`input_file`] for a path already parsed.
pub fn resolve(p: &Path) -> PathBuf {
    if p.is_relative() && !p.exists() {
        if let Some(found) = host::files::find_upwards(p) {
            return found;
        }
    }
    p.to_path_buf()
}

/// Where an output the repository keeps goes by default (`data/default.lut` for `lut build`):
/// under the repository the current folder is in, else relative to the current folder.
pub fn repo_output(rel: &str) -> PathBuf {
    host::files::find_repo().map_or_else(|| PathBuf::from(rel), |r| r.join(rel))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_relative_path_is_found_upwards_and_anything_else_kept() {
        // The tests run in lut/: the repository's table is one folder up.
        let found = resolve(Path::new("data/default.lut"));
        assert!(found.is_absolute() && found.exists(), "{}", found.display());
        assert!(found.ends_with("data/default.lut"));
        // A path that exists here, an absolute one and one found nowhere: as given.
        assert_eq!(
            resolve(Path::new("src/paths.rs")),
            Path::new("src/paths.rs")
        );
        assert_eq!(
            resolve(Path::new("/nonexistent.lut")),
            Path::new("/nonexistent.lut")
        );
        assert_eq!(
            resolve(Path::new("nowhere/x.lut")),
            Path::new("nowhere/x.lut")
        );
        assert!(repo_output("data/default.lut").ends_with("data/default.lut"));
    }
}
