//! What the density benches share.

use std::path::PathBuf;
use std::time::Duration;

/// The directory for a bench's extra results, beside criterion's own: `$CRITERION_HOME`, else `$CARGO_TARGET_DIR/criterion`, else the workspace's `target/criterion`, then `group` (created).
pub fn results_dir(group: &str) -> PathBuf {
    let criterion = std::env::var_os("CRITERION_HOME")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("CARGO_TARGET_DIR").map(|t| PathBuf::from(t).join("criterion"))
        })
        .unwrap_or_else(|| {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/criterion")
        });
    let out = criterion.join(group);
    let _ = std::fs::create_dir_all(&out);
    out
}

/// The middle value of `v` (the upper middle for an even count), 0 for none.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

/// A duration in milliseconds.
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
