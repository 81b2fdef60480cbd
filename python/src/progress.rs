//! Progress of long calls (`evaluate(..., progress=...)`) reported to Python: a line on `sys.stderr`
//! every few seconds (`progress=True`), or a callable given `(task, done, total)`. Worker threads take
//! the GIL only for the report itself.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use pyo3::prelude::*;

/// Reports at most this often (and at the start and end of each task).
const EVERY: Duration = Duration::from_secs(2);

#[derive(Debug)]
pub struct PyProgress {
    /// A callable, or `None` for lines on `sys.stderr`.
    callback: Option<Py<PyAny>>,
    state: Mutex<State>,
}

#[derive(Debug)]
struct State {
    task: String,
    total: Option<u64>,
    done: u64,
    last: Instant,
}

impl PyProgress {
    /// The progress `progress` asks for: `None`/`False` shows nothing, `True` writes lines, a callable
    /// is called.
    pub fn from_arg(progress: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Self>> {
        let Some(progress) = progress else {
            return Ok(None);
        };
        if progress.is_callable() {
            return Ok(Some(Self::new(Some(progress.clone().unbind()))));
        }
        Ok(progress.is_truthy()?.then(|| Self::new(None)))
    }

    fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            state: Mutex::new(State {
                task: String::new(),
                total: None,
                done: 0,
                last: Instant::now(),
            }),
        }
    }

    fn report(&self, task: &str, done: u64, total: Option<u64>) {
        Python::attach(|py| {
            let result = match &self.callback {
                Some(callback) => callback.call1(py, (task, done, total)).map(drop),
                None => {
                    let of = total.map_or_else(String::new, |t| format!(" of {t}"));
                    py.import("sys")
                        .and_then(|sys| sys.getattr("stderr"))
                        .and_then(|err| {
                            err.call_method1("write", (format!("presrs: {task}: {done}{of}\n"),))
                        })
                        .map(drop)
                }
            };
            // A failing callback must not stop the work; Python sees its error as unraisable.
            if let Err(err) = result {
                err.write_unraisable(py, None);
            }
        });
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl presrs::Progress for PyProgress {
    fn start(&self, task: &str, total: Option<u64>) {
        {
            let mut state = self.lock();
            state.task = task.to_owned();
            state.total = total;
            state.done = 0;
            state.last = Instant::now();
        }
        self.report(task, 0, total);
    }

    fn advance(&self, steps: u64) {
        let due = {
            let mut state = self.lock();
            state.done += steps;
            (state.last.elapsed() >= EVERY).then(|| {
                state.last = Instant::now();
                (state.task.clone(), state.done, state.total)
            })
        };
        if let Some((task, done, total)) = due {
            self.report(&task, done, total);
        }
    }

    fn finish(&self) {
        let (task, done, total) = {
            let state = self.lock();
            (state.task.clone(), state.done, state.total)
        };
        self.report(&task, done, total);
    }
}
