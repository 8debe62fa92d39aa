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
}
