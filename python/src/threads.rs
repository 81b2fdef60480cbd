//! The threads batch work runs on: a rayon pool of this process's own. A process forked from one that
//! used rayon (Python's `multiprocessing` and `ProcessPoolExecutor` fork on Linux) inherits the global
//! pool's state but none of its threads, so the first parallel call in the child would wait forever.
//! This pool remembers the process that built it, and a forked child builds its own.

use std::sync::{Arc, Mutex};

use rayon::ThreadPool;

use crate::errors::data_error;

static POOL: Mutex<Option<(u32, Arc<ThreadPool>)>> = Mutex::new(None);

/// Runs `work` on this process's pool (every parallel step inside it included).
pub fn run<T: Send>(work: impl FnOnce() -> T + Send) -> pyo3::PyResult<T> {
    Ok(pool()?.install(work))
}

fn pool() -> pyo3::PyResult<Arc<ThreadPool>> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some((owner, pool)) = slot.as_ref()
        && *owner == pid
    {
        return Ok(Arc::clone(pool));
    }
    if let Some((_, inherited)) = slot.take() {
        // Its threads live in the parent only: never drop (and so never signal) it here.
        std::mem::forget(inherited);
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("presrs-{i}"))
            .build()
            .map_err(|err| data_error(format!("cannot start worker threads: {err}")))?,
    );
    *slot = Some((pid, Arc::clone(&pool)));
    Ok(pool)
}

/// Runs `work` without the GIL, on this process's pool.
pub fn detached<T: Send>(
    py: pyo3::Python<'_>,
    work: impl FnOnce() -> T + Send,
) -> pyo3::PyResult<T> {
    py.detach(|| run(work))
}
