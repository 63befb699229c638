//! Progress bars for the long-running examples, and their command line, included with
//! `#[path = "common/progress.rs"] mod progress;`. The bars are drawn on stderr, so stdout
//! (tables, CSV) stays clean, and only when stderr is a terminal; `--quiet` hides them.
#![allow(dead_code)]

use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// `--quiet` is among the command-line arguments.
pub fn quiet() -> bool {
    std::env::args().any(|a| a == "--quiet")
}

/// The command-line arguments that are not flags (`--...`), program name excluded.
pub fn positional() -> Vec<String> {
    std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect()
}

/// The output folder: the first positional argument, else `default`; created if missing.
pub fn output_dir(default: &str) -> std::io::Result<PathBuf> {
    let dir = PathBuf::from(
        positional()
            .into_iter()
            .next()
            .unwrap_or_else(|| default.into()),
    );
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// A progress bar of `len` units titled `name` on stderr; hidden with `--quiet`.
pub fn bar(len: u64, name: &str) -> ProgressBar {
    if quiet() {
        return ProgressBar::hidden();
    }
    let style =
        ProgressStyle::with_template("{prefix:>16} [{bar:40}] {pos}/{len} {msg} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> ");
    ProgressBar::new(len)
        .with_style(style)
        .with_prefix(name.to_string())
}
