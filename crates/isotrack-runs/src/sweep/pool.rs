//! The worker pool of a sweep (and of the other commands that run in parallel).

use crate::failure::{exit, fail, Failure};

/// The most worker threads per core `--threads` may ask for: beyond a few per core, threads
/// only add scheduling and memory (100 000 threads once stalled a sweep before its first row).
pub const MAX_THREADS_PER_CORE: usize = 8;

/// The thread count to use for `--threads` (capped at [`MAX_THREADS_PER_CORE`] per core), and
/// the note that says so when it was capped (the front end prints it).
pub fn thread_count(requested: Option<usize>) -> (Option<usize>, Option<String>) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cap = MAX_THREADS_PER_CORE * cores;
    let note = requested.filter(|&t| t > cap).map(|t| {
        format!(
            "note: --threads {t} capped to {cap} ({MAX_THREADS_PER_CORE} per core on {cores} cores); results do not depend on it"
        )
    });
    (requested.map(|t| t.clamp(1, cap)), note)
}

/// The worker pool for `--threads` (capped at 8 per core, see [`thread_count`]; all cores by
/// default), and the note about the cap if there is one.
pub fn worker_pool_noted(
    threads: Option<usize>,
) -> Result<(rayon::ThreadPool, Option<String>), Failure> {
    let (count, note) = thread_count(threads);
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = count {
        b = b.num_threads(t);
    }
    let pool = b
        .build()
        .map_err(|e| fail(exit::OSERR, format!("cannot start threads: {e}")))?;
    Ok((pool, note))
}

/// [`worker_pool_noted`] without the note (library callers say it their own way).
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, Failure> {
    worker_pool_noted(threads).map(|(pool, _)| pool)
}
