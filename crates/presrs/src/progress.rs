//! How long work reports its progress: a small trait the caller implements (the command line draws a
//! bar with it; a Python caller or a test may count or ignore the steps).

use std::sync::Mutex;

use presrs_io::message::{Warning, Warnings};

/// Receives the progress of a long workflow. Every method has a do-nothing default, so an
/// implementation overrides what it shows. Called from worker threads too, hence `Sync`.
pub trait Progress: Sync {
    /// A task begins: `total` steps when known, else a spinner's worth of work.
    fn start(&self, _task: &str, _total: Option<u64>) {}
    /// `steps` more steps of the current task are done.
    fn advance(&self, _steps: u64) {}
    /// The current task is over (its bar can go).
    fn finish(&self) {}
    /// The current task has entered a new stage (the automatic choice: its features, its scoring,
    /// training the winner): a display shows it as the task's message.
    fn stage(&self, _stage: &str) {}
    /// Something the user should know that did not stop the work (a file without stance, a capped
    /// option). Workflows that return a result also keep their warnings in it.
    fn warn(&self, _warning: &Warning) {}
    /// Something worth saying as it happens that is not a problem (a draw made smaller to fit the
    /// data, how long a stage took).
    fn note(&self, _message: &str) {}
}

/// Progress that shows nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quiet;

impl Progress for Quiet {}

/// Progress that remembers what it was told: the tasks started, the steps done and the warnings (for
/// tests, and for callers that show them later).
#[derive(Debug, Default)]
pub struct Recorder {
    log: Mutex<RecorderLog>,
}

/// What a [`Recorder`] saw.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecorderLog {
    /// Tasks in the order they started, with their announced totals.
    pub tasks: Vec<(String, Option<u64>)>,
    /// Steps reported over all tasks.
    pub steps: u64,
    pub warnings: Warnings,
    pub notes: Vec<String>,
    /// Stages in the order they began.
    pub stages: Vec<String>,
}

impl Recorder {
    /// What was reported so far.
    pub fn log(&self) -> RecorderLog {
        self.lock().clone()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, RecorderLog> {
        // A panic in another reporting thread leaves the log as it was; it is still worth reading.
        self.log
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl Progress for Recorder {
    fn start(&self, task: &str, total: Option<u64>) {
        self.lock().tasks.push((task.to_owned(), total));
    }

    fn advance(&self, steps: u64) {
        self.lock().steps += steps;
    }

    fn stage(&self, stage: &str) {
        self.lock().stages.push(stage.to_owned());
    }

    fn warn(&self, warning: &Warning) {
        self.lock().warnings.push(warning.clone());
    }

    fn note(&self, message: &str) {
        self.lock().notes.push(message.to_owned());
    }
}
