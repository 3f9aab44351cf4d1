//! One module per command.

pub mod bench;
pub mod canvas;
pub mod check;
pub mod compare;
pub mod grad;
pub mod matching;
pub mod optimize;
pub mod plots;
pub mod render;

/// Runs `f` on a rayon pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    check_threads(threads)?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    Ok(builder.build()?.install(f))
}

/// The `--threads` check: a count, if given, of at least 1.
pub fn check_threads(threads: Option<usize>) -> anyhow::Result<()> {
    anyhow::ensure!(threads != Some(0), "--threads must be at least 1");
    Ok(())
}

/// Peak resident set size of this process in MB (`VmHWM` in
/// `/proc/self/status`); `None` where the OS does not tell.
pub fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
