//! Helpers both native test tiers share (`tests/integration`, `tests/tier2`): where the
//! shared third-party data and the project's fixtures are, and (in [`coverage`]) the
//! harness of the statistical checks, and (in [`jpeg`]) JPEGs as phones write them.
#![allow(dead_code)]

pub mod coverage;
pub mod jpeg;

/// The shared third-party data, `../shared` beside the repository (see its
/// `data/SOURCES.md`); panics, naming the folder, when it is not there.
fn shared_root() -> std::path::PathBuf {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = repo.parent().unwrap_or(repo).join("shared");
    assert!(
        root.is_dir(),
        "{} is missing: the shared third-party data folder `shared` (data/, reference/) must sit \
         beside the repository ({}); these tests read its files where they are",
        root.display(),
        repo.display()
    );
    root
}

/// Path to a file under `../shared`; panics naming the file when it is missing.
pub fn shared(rel: &str) -> std::path::PathBuf {
    let path = shared_root().join(rel);
    assert!(
        path.exists(),
        "{} is missing from the shared data folder (`shared`, beside the repository)",
        path.display()
    );
    path
}

/// Path to a file of the shared test data, `../shared/data/REL` (meshes, datasets).
pub fn data(rel: &str) -> std::path::PathBuf {
    shared(&format!("data/{rel}"))
}

/// Path to a file of the shared reference results, `../shared/reference/REL`.
pub fn reference(rel: &str) -> std::path::PathBuf {
    shared(&format!("reference/{rel}"))
}

/// Path to a project-made fixture under `tests/fixtures` (made by this project's code
/// or scripts, never copied from elsewhere).
pub fn fixture(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("fixtures")
        .join(rel)
}
