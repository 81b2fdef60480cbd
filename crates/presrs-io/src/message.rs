//! Messages that name options as data, and the one warning type.
//!
//! An error or a warning that tells the user to change an option names it as an [`Opt`], not as text:
//! each face renders it in its own words ([`Face`]), `--leave-one-out group` on the command line,
//! `leave_one_out="group"` in Python. `Display` renders the command line's words (the library's
//! reference spelling: logs, Rust callers and the command line print it as is).
//!
//! The library knows both spellings (one table, [`Opt::cli_flag`] and [`Opt::python_name`]) so that a
//! message and the names it uses are checked together; it knows nothing of how a face shows them.

use std::fmt;

/// Whose words a message is rendered in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Face {
    /// The `presrs` command line: options are flags (`--per-class 10`).
    Cli,
    /// The Python package: options are keyword arguments (`per_class=10`); an option Python lacks is
    /// described in words.
    Python,
}

/// An option of the library's workflows that a message can tell the user about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[non_exhaustive]
pub enum Opt {
    /// What the axes of a 3-D array are.
    Axes,
    /// The topic of an MCAP bag to read.
    Topic,
    /// The frame period of a recording whose file does not say it.
    FramePeriod,
    /// The frame of a recording to classify.
    Frame,
    /// Leave one value of a manifest column out at a time.
    LeaveOneOut,
    /// Images per class drawn for training + validation.
    PerClass,
    /// The validation images of a draw (a count or a fraction).
    Validation,
    /// The principal components kept.
    Dims,
    /// The classifier.
    Classifier,
    /// The feature families.
    Features,
    /// The automatic choice's time budget.
    Budget,
    /// Sample stances cut by the start or end of a recording too.
    IncludePartial,
    /// One sample per file (a recording that is one contact).
    OneSamplePerFile,
    /// The terrains to simulate.
    Terrains,
    /// A terrain given as a height-map image.
    TerrainImage,
    /// The gaits to simulate.
    Gaits,
    /// The gait a simulated track starts with.
    StartGait,
    /// The gait a simulated track keeps.
    FixedGait,
    /// Hops recorded per terrain and gait.
    HopsPerGait,
    /// Latency measurements of the benchmark.
    Iterations,
    /// Images per batch of the benchmark.
    Batch,
    /// Batches of the benchmark.
    BatchRuns,
    /// Replace what an earlier run wrote in an output folder.
    Force,
    /// How the automatic choice validates its candidates inside the training data.
    ValidateBy,
    /// The one condition an evaluation trains on.
    TrainCondition,
    /// What a sample is: one frame, a whole stance, a series.
    Sample,
    /// When a whole-stance model decides online: K frames after touchdown.
    DecideAt,
    /// Frames each whole-stance sample is laid into.
    StanceLength,
    /// The axis that is time in a series sample.
    SeriesAxis,
    /// Which frame of each stance a one-frame sample is.
    StanceFrame,
    /// The frame a one-frame model classifies online: K frames after touchdown.
    SampleOffset,
    /// The frame offsets whose posteriors a one-frame model fuses online.
    Fuse,
}

/// What Python calls an option.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PythonName {
    /// A keyword argument of that name.
    Argument(&'static str),
    /// Python has no such argument: words that say what the option does.
    Words(&'static str),
}

impl Opt {
    /// Every option, for tests that render them all.
    pub const ALL: [Opt; 32] = [
        Opt::Axes,
        Opt::Topic,
        Opt::FramePeriod,
        Opt::Frame,
        Opt::LeaveOneOut,
        Opt::PerClass,
        Opt::Validation,
        Opt::Dims,
        Opt::Classifier,
        Opt::Features,
        Opt::Budget,
        Opt::IncludePartial,
        Opt::OneSamplePerFile,
        Opt::Terrains,
        Opt::TerrainImage,
        Opt::Gaits,
        Opt::StartGait,
        Opt::FixedGait,
        Opt::HopsPerGait,
        Opt::Iterations,
        Opt::Batch,
        Opt::BatchRuns,
        Opt::Force,
        Opt::ValidateBy,
        Opt::TrainCondition,
        Opt::Sample,
        Opt::DecideAt,
        Opt::StanceLength,
        Opt::SeriesAxis,
        Opt::StanceFrame,
        Opt::SampleOffset,
        Opt::Fuse,
    ];

    /// The command line's flag, e.g. `--per-class`.
    pub fn cli_flag(self) -> &'static str {
        match self {
            Self::Axes => "--axes",
            Self::Topic => "--topic",
            Self::FramePeriod => "--frame-period",
            Self::Frame => "--frame",
            Self::LeaveOneOut => "--leave-one-out",
            Self::PerClass => "--per-class",
            Self::Validation => "--validation",
            Self::Dims => "--dims",
            Self::Classifier => "--classifier",
            Self::Features => "--features",
            Self::Budget => "--budget",
            Self::IncludePartial => "--include-partial",
            Self::OneSamplePerFile => "--one-sample-per-file",
            Self::Terrains => "--terrains",
            Self::TerrainImage => "--terrain-image",
            Self::Gaits => "--gaits",
            Self::StartGait => "--start-gait",
            Self::FixedGait => "--fixed-gait",
            Self::HopsPerGait => "--hops-per-gait",
            Self::Iterations => "--iterations",
            Self::Batch => "--batch",
            Self::BatchRuns => "--batch-runs",
            Self::Force => "--force",
            Self::ValidateBy => "--validate-by",
            Self::TrainCondition => "--train-condition",
            Self::Sample => "--sample",
            Self::DecideAt => "--decide-at",
            Self::StanceLength => "--stance-length",
            Self::SeriesAxis => "--series-axis",
            Self::StanceFrame => "--stance-frame",
            Self::SampleOffset => "--sample-offset",
            Self::Fuse => "--fuse",
        }
    }

    /// The Python package's keyword argument (`presrs.read`, `Model.train`, `presrs.evaluate`,
    /// `presrs.simulate`, `Recording`), or words where it has none.
    pub fn python_name(self) -> PythonName {
        use PythonName::{Argument, Words};
        match self {
            Self::Axes => Argument("axes"),
            Self::Topic => Argument("topic"),
            Self::FramePeriod => Argument("frame_period_s"),
            Self::Frame => Words("the frame index"),
            Self::LeaveOneOut => Argument("leave_one_out"),
            Self::PerClass => Argument("per_class"),
            Self::Validation => Argument("validation"),
            Self::Dims => Argument("dims"),
            Self::Classifier => Argument("classifier"),
            Self::Features => Argument("features"),
            Self::Budget => Argument("budget"),
            Self::IncludePartial => Argument("include_partial"),
            Self::OneSamplePerFile => Argument("one_sample_per_file"),
            Self::Terrains => Argument("terrains"),
            Self::TerrainImage => Words("a terrain height-map image"),
            Self::Gaits => Argument("gaits"),
            Self::StartGait => Words("the start gait"),
            Self::FixedGait => Words("the fixed gait"),
            Self::HopsPerGait => Argument("hops"),
            Self::Iterations => Words("the iterations"),
            Self::Batch => Words("the batch size"),
            Self::BatchRuns => Words("the batch runs"),
            Self::Force => Words("permission to replace it (an option of the presrs command line)"),
            Self::ValidateBy => Argument("validate_by"),
            Self::TrainCondition => Argument("train_condition"),
            Self::Sample => Argument("sample"),
            Self::DecideAt => Argument("decide_at"),
            Self::StanceLength => Argument("stance_length"),
            Self::SeriesAxis => Argument("series_axis"),
            Self::StanceFrame => Words("the stance frame (an option of the presrs command line)"),
            Self::SampleOffset => Words("the sample offset (an option of the presrs command line)"),
            Self::Fuse => Words("the fusion offsets (an option of the presrs command line)"),
        }
    }

    /// The option (with its value, if any) in `face`'s words.
    fn render(self, face: Face, value: Option<&Value>) -> String {
        match (face, self.python_name(), value) {
            (Face::Cli, _, None) => self.cli_flag().to_owned(),
            (Face::Cli, _, Some(Value::Plain(v) | Value::Text(v))) => {
                format!("{} {v}", self.cli_flag())
            }
            (Face::Python, PythonName::Argument(name), None) => format!("{name}="),
            (Face::Python, PythonName::Argument(name), Some(Value::Plain(v))) => {
                format!("{name}={v}")
            }
            (Face::Python, PythonName::Argument(name), Some(Value::Text(v))) => {
                format!("{name}={v:?}")
            }
            (Face::Python, PythonName::Words(words), None) => words.to_owned(),
            (Face::Python, PythonName::Words(words), Some(Value::Plain(v) | Value::Text(v))) => {
                format!("{words} {v}")
            }
        }
    }
}

/// An option's value as a message shows it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
enum Value {
    /// A number or a word shown as is in every face (`--dims 5`, `dims=5`).
    Plain(String),
    /// A string a Python caller passes quoted (`--leave-one-out group`, `leave_one_out="group"`).
    Text(String),
}

/// One piece of a message.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
enum Part {
    Text(String),
    Opt(Opt, Option<Value>),
}

/// A message for the user whose options are data: text and [`Opt`]s, rendered by [`Message::render`]
/// in a face's words. Built piece by piece:
///
/// ```
/// use presrs_io::message::{Face, Message, Opt};
/// let message = Message::new().opt_is(Opt::Dims, 40).text(": too many components");
/// assert_eq!(message.render(Face::Cli), "--dims 40: too many components");
/// assert_eq!(message.render(Face::Python), "dims=40: too many components");
/// assert_eq!(message.to_string(), "--dims 40: too many components");
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Message {
    parts: Vec<Part>,
}

impl Message {
    /// An empty message.
    pub fn new() -> Self {
        Self::default()
    }

    /// `text` added at the end.
    #[must_use]
    pub fn text(mut self, text: impl Into<String>) -> Self {
        let text = text.into();
        if !text.is_empty() {
            self.parts.push(Part::Text(text));
        }
        self
    }

    /// The option, named without a value (`--budget`, `budget=`).
    #[must_use]
    pub fn opt(mut self, opt: Opt) -> Self {
        self.parts.push(Part::Opt(opt, None));
        self
    }

    /// The option with a number or keyword value (`--dims 5`, `dims=5`).
    #[must_use]
    pub fn opt_is(mut self, opt: Opt, value: impl fmt::Display) -> Self {
        self.parts
            .push(Part::Opt(opt, Some(Value::Plain(value.to_string()))));
        self
    }

    /// The option with a string value, quoted in Python (`--leave-one-out group`,
    /// `leave_one_out="group"`).
    #[must_use]
    pub fn opt_text(mut self, opt: Opt, value: impl fmt::Display) -> Self {
        self.parts
            .push(Part::Opt(opt, Some(Value::Text(value.to_string()))));
        self
    }

    /// `other` added at the end.
    #[must_use]
    pub fn then(mut self, other: Message) -> Self {
        self.parts.extend(other.parts);
        self
    }

    /// The options the message names, in order.
    pub fn options(&self) -> impl Iterator<Item = Opt> + '_ {
        self.parts.iter().filter_map(|part| match part {
            Part::Opt(opt, _) => Some(*opt),
            Part::Text(_) => None,
        })
    }

    /// The message in `face`'s words.
    pub fn render(&self, face: Face) -> String {
        let mut out = String::new();
        for part in &self.parts {
            match part {
                Part::Text(text) => out.push_str(text),
                Part::Opt(opt, value) => out.push_str(&opt.render(face, value.as_ref())),
            }
        }
        out
    }
}

/// The command line's words (see the module's documentation).
impl fmt::Display for Message {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render(Face::Cli))
    }
}

impl From<String> for Message {
    fn from(text: String) -> Self {
        Self::new().text(text)
    }
}

impl From<&str> for Message {
    fn from(text: &str) -> Self {
        Self::new().text(text)
    }
}

/// Something the user should know that did not stop the work (a dropped truncated frame, a capped
/// option); each face shows it in its words ([`Warning::render`]).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Warning {
    message: Message,
}

impl Warning {
    /// A warning saying `message`.
    pub fn new(message: impl Into<Message>) -> Self {
        Self {
            message: message.into(),
        }
    }

    /// What the warning says.
    pub fn message(&self) -> &Message {
        &self.message
    }

    /// The warning in `face`'s words.
    pub fn render(&self, face: Face) -> String {
        self.message.render(face)
    }
}

/// The command line's words.
impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.message.fmt(f)
    }
}

/// As its command-line text: the JSON documents (`inspect --json`, `classify --json`) are the
/// command line's.
impl serde::Serialize for Warning {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(&self.message)
    }
}

impl From<Message> for Warning {
    fn from(message: Message) -> Self {
        Self { message }
    }
}

impl From<String> for Warning {
    fn from(text: String) -> Self {
        Self::new(text)
    }
}

impl From<&str> for Warning {
    fn from(text: &str) -> Self {
        Self::new(text)
    }
}

/// The warnings of a result, in the order they were found (a slice through `Deref`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Warnings(Vec<Warning>);

impl Warnings {
    /// No warning.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a warning saying `message`.
    pub fn push(&mut self, message: impl Into<Warning>) {
        self.0.push(message.into());
    }

    /// Every warning in `face`'s words.
    pub fn render(&self, face: Face) -> Vec<String> {
        self.0.iter().map(|warning| warning.render(face)).collect()
    }

    /// Sorted by their command-line text (a stable order for warnings gathered in parallel).
    pub fn sort_by_text(&mut self) {
        self.0.sort_by_cached_key(ToString::to_string);
    }
}

/// As a list of their command-line texts (see [`Warning`]'s).
impl serde::Serialize for Warnings {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(&self.0)
    }
}

impl std::ops::Deref for Warnings {
    type Target = [Warning];

    fn deref(&self) -> &[Warning] {
        &self.0
    }
}

impl<W: Into<Warning>> Extend<W> for Warnings {
    fn extend<I: IntoIterator<Item = W>>(&mut self, iter: I) {
        self.0.extend(iter.into_iter().map(Into::into));
    }
}

impl<W: Into<Warning>> FromIterator<W> for Warnings {
    fn from_iter<I: IntoIterator<Item = W>>(iter: I) -> Self {
        Self(iter.into_iter().map(Into::into).collect())
    }
}

impl IntoIterator for Warnings {
    type Item = Warning;
    type IntoIter = std::vec::IntoIter<Warning>;

    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<'a> IntoIterator for &'a Warnings {
    type Item = &'a Warning;
    type IntoIter = std::slice::Iter<'a, Warning>;

    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `text` holds a command-line flag: `--` followed by a letter.
    fn names_a_flag(text: &str) -> bool {
        text.as_bytes()
            .windows(3)
            .any(|w| w[0] == b'-' && w[1] == b'-' && w[2].is_ascii_alphabetic())
    }

    #[test]
    fn every_option_renders_in_both_faces() {
        for opt in Opt::ALL {
            let flag = opt.cli_flag();
            assert!(
                flag.starts_with("--") && names_a_flag(flag),
                "{opt:?}: {flag}"
            );
            let bare = Message::new().opt(opt);
            let valued = Message::new().opt_is(opt, 7);
            let text = Message::new().opt_text(opt, "group");
            assert_eq!(bare.render(Face::Cli), flag);
            assert_eq!(valued.render(Face::Cli), format!("{flag} 7"));
            assert_eq!(text.render(Face::Cli), format!("{flag} group"));
            assert_eq!(bare.to_string(), flag, "Display is the command line's");
            for python in [bare.render(Face::Python), valued.render(Face::Python)] {
                assert!(!names_a_flag(&python), "{opt:?}: {python}");
                assert!(!python.is_empty());
            }
            match opt.python_name() {
                PythonName::Argument(name) => {
                    assert!(
                        name.chars().all(|c| c.is_ascii_lowercase() || c == '_'),
                        "{opt:?}: {name}"
                    );
                    assert_eq!(bare.render(Face::Python), format!("{name}="));
                    assert_eq!(valued.render(Face::Python), format!("{name}=7"));
                    assert_eq!(text.render(Face::Python), format!("{name}=\"group\""));
                }
                PythonName::Words(words) => {
                    assert!(words.contains(' '), "{opt:?}: {words}");
                    assert_eq!(bare.render(Face::Python), words);
                }
            }
        }
    }

    #[test]
    fn every_option_is_listed_once() {
        let mut flags: Vec<&str> = Opt::ALL.iter().map(|o| o.cli_flag()).collect();
        flags.sort_unstable();
        flags.dedup();
        assert_eq!(flags.len(), Opt::ALL.len());
    }

    #[test]
    fn a_message_keeps_its_text_and_options_in_order() {
        let message = Message::from("a.csv: ")
            .opt_text(Opt::LeaveOneOut, "site")
            .text(": no such column; ")
            .then(Message::new().text("try ").opt(Opt::IncludePartial));
        assert_eq!(
            message.to_string(),
            "a.csv: --leave-one-out site: no such column; try --include-partial"
        );
        assert_eq!(
            message.render(Face::Python),
            "a.csv: leave_one_out=\"site\": no such column; try include_partial="
        );
        assert_eq!(
            message.options().collect::<Vec<_>>(),
            [Opt::LeaveOneOut, Opt::IncludePartial]
        );
    }

    #[test]
    fn warnings_render_sort_and_collect() {
        let mut warnings = Warnings::new();
        warnings.push("b: plain");
        warnings.push(Message::new().text("a: ").opt_is(Opt::Budget, 0));
        assert_eq!(warnings.len(), 2);
        warnings.sort_by_text();
        assert_eq!(warnings.render(Face::Cli), ["a: --budget 0", "b: plain"]);
        assert_eq!(warnings.render(Face::Python), ["a: budget=0", "b: plain"]);
        let copied: Warnings = warnings.iter().cloned().collect();
        assert_eq!(copied, warnings);
        assert_eq!(
            serde_json::to_string(&warnings).unwrap_or_default(),
            r#"["a: --budget 0","b: plain"]"#
        );
    }
}
