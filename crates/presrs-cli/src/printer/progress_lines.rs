//! A task's progress told as a line every so often, for logs (where a bar cannot be drawn): a thread
//! of its own hands `TASK: DONE/TOTAL (N s)` to a sink at each interval while the task runs.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Where the lines go (the command line: `progress: LINE` on stderr).
pub type LineSink = Arc<dyn Fn(&str) + Send + Sync>;

/// The task running and how far it got; a task's thread stops when the task is replaced or finished.
pub struct ProgressLines {
    running: Arc<Mutex<Option<LoggedTask>>>,
    interval: Duration,
    sink: LineSink,
}

impl std::fmt::Debug for ProgressLines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProgressLines")
            .field("running", &self.running)
            .field("interval", &self.interval)
            .finish_non_exhaustive()
    }
}

/// A task whose progress is logged as lines.
#[derive(Debug)]
struct LoggedTask {
    task: String,
    total: Option<u64>,
    done: u64,
    started: Instant,
}

impl ProgressLines {
    /// Lines every `interval` to `sink`.
    pub fn new(interval: Duration, sink: LineSink) -> Self {
        Self {
            running: Arc::default(),
            interval,
            sink,
        }
    }

    fn running(&self) -> MutexGuard<'_, Option<LoggedTask>> {
        self.running
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Starts logging `task` (replacing any task running): a thread writes a line every interval until
    /// the task is finished or replaced, or this is dropped.
    pub fn start(&self, task: &str, total: Option<u64>) {
        let started = Instant::now();
        *self.running() = Some(LoggedTask {
            task: task.to_owned(),
            total,
            done: 0,
            started,
        });
        let running = Arc::downgrade(&self.running);
        let (interval, sink) = (self.interval, self.sink.clone());
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(interval);
                let Some(running) = running.upgrade() else {
                    return;
                };
                let guard = running
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner());
                match guard.as_ref() {
                    // This thread's task, still running.
                    Some(t) if t.started == started => {
                        sink(&progress_line(
                            &t.task,
                            t.done,
                            t.total,
                            t.started.elapsed(),
                        ));
                    }
                    _ => return,
                }
            }
        });
    }

    /// `steps` more steps of the running task are done.
    pub fn advance(&self, steps: u64) {
        if let Some(task) = self.running().as_mut() {
            task.done += steps;
        }
    }

    /// The running task is over: no more lines about it.
    pub fn finish(&self) {
        self.running().take();
    }
}

/// How often progress lines are written: `PRESRS_PROGRESS_SECONDS` (seconds, e.g. 0.5), else 5 s.
pub fn progress_interval() -> Duration {
    std::env::var("PRESRS_PROGRESS_SECONDS")
        .ok()
        .and_then(|text| text.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .map_or(Duration::from_secs(5), |s| {
            Duration::from_secs_f64(s.min(1e6))
        })
}

/// One progress line: `TASK: DONE/TOTAL (N s)`, or `TASK: N s` for a task of unknown length.
pub fn progress_line(task: &str, done: u64, total: Option<u64>, elapsed: Duration) -> String {
    let seconds = elapsed.as_secs_f64();
    match total {
        Some(total) => format!("{task}: {done}/{total} ({seconds:.0} s)"),
        None => format!("{task}: {seconds:.0} s"),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn progress_lines_say_how_far_and_how_long() {
        let ten = Duration::from_secs(10);
        assert_eq!(
            progress_line("training", 3, Some(40), ten),
            "training: 3/40 (10 s)"
        );
        assert_eq!(progress_line("training", 0, None, ten), "training: 10 s");
    }

    #[test]
    fn a_running_task_is_logged_until_it_finishes() {
        let lines = Arc::new(Mutex::new(Vec::<String>::new()));
        let sink = {
            let lines = lines.clone();
            Arc::new(move |line: &str| lines.lock().unwrap().push(line.to_owned()))
        };
        let progress = ProgressLines::new(Duration::from_millis(20), sink);
        progress.start("training", Some(4));
        progress.advance(3);
        std::thread::sleep(Duration::from_millis(150));
        progress.finish();
        std::thread::sleep(Duration::from_millis(20));
        let seen = lines.lock().unwrap().clone();
        assert!(!seen.is_empty());
        assert!(
            seen.iter().all(|l| l.starts_with("training: 3/4 (")),
            "{seen:?}"
        );
        std::thread::sleep(Duration::from_millis(40));
        assert_eq!(
            lines.lock().unwrap().len(),
            seen.len(),
            "lines after finish"
        );
    }
}
