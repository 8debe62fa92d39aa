//! Where a bench tool finds the repository's files (`data/`, `scenarios/`, the DBC) when the
//! user has not named them: walking up from the current folder, then from the executable's
//! (`target/release/ecu` lies inside the repository). Never the folder the binary was built in:
//! a copied or moved checkout, or a tool started from a sub-folder, finds its own files.

use std::path::{Path, PathBuf};

/// `rel` under the first folder that holds it, walking up from the current directory, then
/// from the executable's folder.
pub fn find_upwards(rel: &Path) -> Option<PathBuf> {
    let starts = [
        std::env::current_dir().ok(),
        std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Path::to_path_buf)),
    ];
    starts
        .into_iter()
        .flatten()
        .find_map(|start| start.ancestors().map(|a| a.join(rel)).find(|p| p.exists()))
}

/// A file only the bench's repository has (its one bus definition).
const REPO_MARK: &str = "bus/restraint.dbc";

/// The repository the user is in (walking up from the current folder, then from the
/// executable's); `None` outside any checkout.
pub fn find_repo() -> Option<PathBuf> {
    find_upwards(Path::new(REPO_MARK)).and_then(|dbc| dbc.parent()?.parent().map(Path::to_path_buf))
}

/// Checks, before a run, that an output file can be written at its end: makes its folder and
/// opens the file for writing (without truncating; a file the probe created is removed
/// again). A run that would only fail at its end — after minutes — fails at once instead.
/// `-` (stdout) is always writable.
pub fn check_output_file(path: &Path) -> std::io::Result<()> {
    if crate::results::is_stdout(path) {
        return Ok(());
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Makes an output folder before a run (and checks it is one).
pub fn check_output_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)
}

/// A writer whose `flush` does nothing, around one that the caller flushes on its own
/// schedule. For a serializer that flushes after every record (`postcard::to_io`) writing into
/// a `BufWriter`: flushed per record, a log is one `write()` per record, and on a guest's
/// shared folder each is a round trip to the host.
pub struct NoFlush<W>(pub W);

impl<W: std::io::Write> std::io::Write for NoFlush<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.0.write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The folders under `root` (itself and up to three levels down, as a bench's run folders lie:
/// `OUT/<scenario>/`, the campaign's `OUT/<guest>/<case>/<scenario>/`) that hold a file
/// `name`, sorted: the runs that left work for the host (a recording, a picture).
///
/// # Errors
/// A folder cannot be read.
pub fn run_folders_holding(root: &Path, name: &str) -> std::io::Result<Vec<PathBuf>> {
    fn walk(dir: &Path, name: &str, depth: usize, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
        if dir.join(name).is_file() {
            out.push(dir.to_path_buf());
        }
        if depth < 3 {
            for e in std::fs::read_dir(dir)? {
                let e = e?;
                if e.file_type()?.is_dir() {
                    walk(&e.path(), name, depth + 1, out)?;
                }
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(root, name, 0, &mut out)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", root.display())))?;
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_repository_is_found_from_inside_it() {
        // cargo runs unit tests in the crate's folder, inside the repository.
        let repo = find_repo().expect("inside the checkout");
        assert!(repo.join(REPO_MARK).is_file(), "{}", repo.display());
        assert!(repo.join("host").is_dir(), "{}", repo.display());
        assert_eq!(find_upwards(Path::new("no/such/file-x9")), None);
    }

    #[test]
    fn output_files_are_checked_before_the_run() {
        let dir = std::env::temp_dir().join(format!("host-out-{}", std::process::id()));
        let file = dir.join("a/b/report.json");
        check_output_file(&file).expect("folder made");
        assert!(
            dir.join("a/b").is_dir() && !file.exists(),
            "probe left no file"
        );
        std::fs::write(&file, "kept").expect("write");
        check_output_file(&file).expect("existing file");
        assert_eq!(std::fs::read_to_string(&file).expect("read"), "kept");
        assert!(check_output_file(Path::new("/proc/no-such-dir/x.json")).is_err());
        assert!(check_output_file(&dir.join("a/b/report.json/x")).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Writes pass through; flushes stop here (the inner writer sees none).
    #[test]
    fn no_flush_passes_writes_and_keeps_flushes() {
        use std::io::Write;
        struct Inner(Vec<u8>, usize);
        impl Write for Inner {
            fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
                self.0.extend_from_slice(buf);
                Ok(buf.len())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                self.1 += 1;
                Ok(())
            }
        }
        let mut inner = Inner(Vec::new(), 0);
        let mut w = NoFlush(&mut inner);
        w.write_all(b"ab").expect("write");
        w.write_all(b"c").expect("write");
        w.flush().expect("flush");
        assert_eq!((inner.0.as_slice(), inner.1), (&b"abc"[..], 0));
    }
}
