//! Options and helpers shared by several subcommands.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use presrs::dataset::{
    DeadSenselFills, GivenSampleSettings, SampleChoice, SampleKind, SampleOptions,
    check_sample_settings, read_corrected,
};
use presrs::method::{ClassifierChoice, CropChoice, FeatureChoice, Method, ValidateBy};
use presrs::{Dataset, Progress};
use presrs_core::Recording;
use presrs_core::dead_sensels::DeadSenselConfig;
use presrs_core::preprocess::Preprocess;
use presrs_core::stance::{BaselineMode, SampleFrame, SegmentParams, ValidSegmentParams};
use presrs_io::{ArrayAxes, ReadOptions};

use super::usage::UsageError;
use crate::printer::progress_lines::{ProgressLines, progress_interval};

/// How the pipeline is built: crop, features, reduction, classifier.
#[derive(Debug, Clone, clap::Args)]
pub struct PipelineArgs {
    /// Feature family: fft1d (the paper's 1-D |FFT| of the row-major image), fft2d (half 2-D |FFT|),
    /// fft2d_polar (ring and wedge sums of the 2-D |FFT|), glcm (co-occurrence texture attributes),
    /// contact (the contact's areas, lengths, elongation, load and radial profile, standardised over the
    /// training images; not raced by auto), rocket
    /// (MiniRocket over a series: rows are channels, each scaled by its spread; with --sample stance or
    /// series), rocket_unscaled (the channels in their own units), rocket_log (a signed log of every
    /// value first), rocket_duration and rocket_log_duration (a whole stance's duration as one more
    /// feature), multirocket, multirocket_unscaled (MultiRocket: the series and its first differences,
    /// four poolings); join
    /// several with + (fft1d+glcm); or auto (the default: chosen by validation inside the training data,
    /// by group or condition (--validate-by), among every family: the FFT ones first, then fft1d after
    /// sqrt and log1p, then glcm and fft2d_polar+glcm, as far as --budget allows; with --sample stance
    /// or series among rocket_unscaled and rocket, or with --full-search every family, the random
    /// convolutions first). `--features fft1d --classifier pwe` is the paper's method.
    #[arg(long, default_value = "auto", value_parser = |t: &str| t.parse::<FeatureChoice>())]
    pub features: FeatureChoice,
    /// Classifier: pwe (Parzen window, the paper's), mle (Gaussian, shrunk full covariance per class),
    /// lda (shared covariance), svm (one-vs-one, linear or RBF, C and gamma chosen on validation), knn,
    /// ridge (one-vs-rest, for the rocket families; it takes every feature, standardised, with no PCA
    /// step), ridge_raw (the same on centred, unscaled features); or auto (the default: chosen by validation inside the training
    /// data among the first five).
    #[arg(long, default_value = "auto", value_parser = |t: &str| t.parse::<ClassifierChoice>())]
    pub classifier: ClassifierChoice,
    /// With auto: score every candidate whatever the time it takes (as --budget 0), and with --sample
    /// stance or series race every family (MultiRocket and the frame families too), not MiniRocket's
    /// two alone.
    #[arg(long)]
    pub full_search: bool,
    /// With auto: seconds the automatic choice may spend scoring its candidates, per model trained (in
    /// eval, per fold and repeat); the texture families, scored last, are cut first, with a warning.
    /// 0: no limit (every candidate is tried, and the choice does not depend on the machine's speed).
    #[arg(long, value_name = "SECONDS", default_value = "60", value_parser = parse_budget)]
    pub budget: Budget,
    /// With auto: how the winner is picked from the validation scores: best (the highest mean),
    /// one-se (the earliest candidate in the search order, which lists the paper's method first, the
    /// costlier families last and on whole samples MiniRocket with ridge first, within one standard
    /// error of the best; the best with fewer than 3 validation folds) or auto (one-se on stances and
    /// series, best on frames). Under each a tie for the best goes to the prior (rocket + svm on whole
    /// samples)
    #[arg(long, default_value = "auto", value_parser = |t: &str| t.parse::<presrs::method::Choose>())]
    pub choose: presrs::method::Choose,
    /// Principal components kept, at least 1 (at most the number of training images minus one, and the
    /// number of features: a larger value is lowered to that, with a warning when given) [default: 51];
    /// ridge has no PCA step and ignores it.
    #[arg(long, value_name = "DIMS", value_parser = crate::args::values::positive_count)]
    pub dims: Option<usize>,
    /// Divide each cropped image by its total load (sum of its values): features that do not depend on
    /// the robot's load, without knowing it. Stored in the model; off in the paper's method.
    #[arg(long)]
    pub normalise_load: bool,
    /// Fill absent (masked) sensels from their neighbours (mean of the 4-neighbours, relaxed across
    /// clusters) instead of reading them as 0. Stored in the model.
    #[arg(long)]
    pub fill_absent: bool,
    /// Transform each image value before the features: none, sqrt or log1p (the sign kept); stored in
    /// the model. With --features auto and none, the automatic choice tries sqrt and log1p as well.
    #[arg(long, default_value = "none", value_parser = |t: &str| t.parse::<presrs_core::preprocess::Intensity>().map_err(|e| e.to_string()))]
    pub intensity: presrs_core::preprocess::Intensity,
    /// With auto: how the candidates are validated inside the training data: group (leave one of the
    /// manifest's `group` out), condition (leave one condition out), split (three stratified 70/30
    /// splits), or auto (group when the training data hold 3 or more groups, else condition when they
    /// hold several, else split).
    #[arg(long, default_value = "auto", value_parser = |t: &str| t.parse::<ValidateBy>())]
    pub validate_by: ValidateBy,
    #[command(flatten)]
    pub crop: CropArg,
}

/// The `--crop` option.
#[derive(Debug, Clone, clap::Args)]
pub struct CropArg {
    /// Region of each image used: auto (the paper's crop on a 44x44 array, the whole image otherwise),
    /// paper (drop the bottom 6 rows and first 3 columns: 44x44 -> 38x41), none, margins
    /// top,bottom,left,right, or a window row0:col0:rows:cols.
    #[arg(long = "crop", default_value = "auto", value_parser = |t: &str| t.parse::<CropChoice>())]
    pub crop: CropChoice,
}

impl PipelineArgs {
    /// The method these options describe (`auto` parts chosen by validation).
    pub fn method(&self) -> Method {
        Method {
            features: self.features.clone(),
            classifier: self.classifier,
            full_search: self.full_search,
            budget: self.budget.0,
            dims: self.dims,
            preprocess: Preprocess {
                normalise_load: self.normalise_load,
                fill_absent: self.fill_absent,
                intensity: self.intensity,
            },
            crop: self.crop.crop,
            validate_by: self.validate_by,
            choose: self.choose,
        }
    }
}

/// A time budget (`None`: no limit), as clap keeps it.
#[derive(Debug, Clone, Copy)]
pub struct Budget(Option<std::time::Duration>);

/// A time budget in seconds (a non-negative number; 0: no limit).
fn parse_budget(text: &str) -> Result<Budget, String> {
    let seconds: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a number of seconds (e.g. 60, or 0 for no limit)"))?;
    presrs::method::budget_from_seconds(seconds).map(Budget)
}

/// How samples are taken from movies.
#[derive(Debug, Clone, clap::Args)]
pub struct SampleArgs {
    /// What a sample is: frame (a frame of each stance, --stance-frame), stance (each stance's movie as
    /// load, contact area, centre of pressure and regional loads over time), or series (a 2-D array as
    /// channels x time); train, eval and report also take auto (one frame against the whole sample,
    /// by validation inside the training data)
    #[arg(long, default_value = "frame", value_parser = sample_choice_parser())]
    pub sample: SampleChoice,
    /// With --sample stance: frames each stance is laid into (default: the longest stance; at most 4
    /// times it)
    #[arg(long)]
    pub stance_length: Option<usize>,
    /// With --sample series: the array's axis that is time, cols (rows are channels) or rows
    #[arg(long, value_parser = ["cols", "rows"])]
    pub series_axis: Option<String>,
    /// With --sample frame: which frame of each stance phase is a sample: mid (the paper's mid-stance
    /// frame), peak, a frame offset K after touchdown (0-based), or all [default: mid].
    #[arg(long, value_parser = parse_sample_frame)]
    pub stance_frame: Option<SampleFrame>,
    /// Also use stances cut by the start or end of a recording.
    #[arg(long)]
    pub include_partial: bool,
    /// Accept a TekScan file whose last frame is truncated (the frame is dropped with a warning) or whose
    /// frame numbers repeat or go back (the frames are kept, with a warning).
    #[arg(long)]
    pub lenient: bool,
    /// Use recordings as read. By default a sensel that reads 0 in every frame of a movie while its
    /// neighbours carry load around it (in 3 frames or more) is taken for dead and filled, in every
    /// frame, from its live neighbours; single images (PNG, 2-D NPY, text, one-frame files) are never
    /// corrected, as one image cannot tell a dead sensel from a gap in the terrain.
    #[arg(long)]
    pub keep_dead_sensels: bool,
    #[command(flatten)]
    pub axes: AxesArg,
    #[command(flatten)]
    pub stance: StanceArgs,
}

/// The options of some formats: `--axes` of array (`.npy`) inputs, `--topic` of ROS 2 bags (`.mcap`).
#[derive(Debug, Clone, clap::Args)]
pub struct AxesArg {
    /// What the axes of a 3-D .npy array are, in the file's order: frames,rows,cols (the default) or
    /// rows,cols,frames (time last, as some exporters write; a warning names this option when the
    /// shape looks like it). Other files ignore it.
    #[arg(long, value_name = "frames,rows,cols", value_parser = |t: &str| t.parse::<ArrayAxes>())]
    pub axes: Option<ArrayAxes>,
    /// The topic of an MCAP file (a ROS 2 bag) to read frames from: sensor_msgs/msg/Image (mono8,
    /// mono16, 16UC1, 32FC1) or std_msgs/msg/Float32MultiArray / UInt16MultiArray with a 2-D layout
    /// [default: the only topic holding frames; `presrs inspect FILE.mcap` lists them]. A manifest's
    /// `topic` column gives it per row. Other files ignore it.
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
}

/// How stance phases are found in movies (the detector's settings; `train` stores them in the model).
#[derive(Debug, Clone, clap::Args)]
pub struct StanceArgs {
    /// What a stance's load rises above: auto (chosen from the data, and said by `inspect`), drifting
    /// (the unloaded level between stances, non-zero or drifting), floor (the local floor: presses or
    /// steps on a standing preload), contact (the whole recording is one contact).
    #[arg(long, value_name = "MODE", default_value = "auto", value_parser = parse_baseline_mode)]
    pub stance_baseline: BaselineMode,
    /// A stance must somewhere exceed this fraction of the load range above the baseline (or floor)
    /// [default: 0.10].
    #[arg(long, value_name = "FRACTION", value_parser = crate::args::values::fraction)]
    pub stance_threshold: Option<f64>,
    /// Hysteresis: a frame belongs to a stance while its load exceeds this fraction of the load range
    /// above the baseline (or floor), at most --stance-threshold [default: 0.01].
    #[arg(long, value_name = "FRACTION", value_parser = crate::args::values::fraction)]
    pub stance_hysteresis: Option<f64>,
    /// Shortest stance kept, in frames [default: 3].
    #[arg(long, value_name = "FRAMES", value_parser = crate::args::values::positive_count)]
    pub stance_min_frames: Option<usize>,
    /// Longest stance kept, in frames (default: no limit); with --stance-baseline auto a longer one
    /// is taken for a standing preload and measured from the local floor.
    #[arg(long, value_name = "FRAMES", value_parser = crate::args::values::positive_count)]
    pub stance_max_frames: Option<usize>,
    /// Fewest unloaded frames between two stances: a shorter dropout inside a stance is bridged
    /// [default: 3].
    #[arg(long, value_name = "FRAMES", value_parser = crate::args::values::positive_count)]
    pub stance_min_gap: Option<usize>,
    /// Every movie is one contact (trials cut to one foot contact, loaded from the first frame to the
    /// last): one sample from each, the whole recording being its stance.
    #[arg(long)]
    pub one_sample_per_file: bool,
    /// Frame period in seconds of files whose format states none (.npy, text, PNG); a manifest's
    /// `frame_period_s` column gives it per file.
    #[arg(long, value_name = "SECONDS", value_parser = crate::args::values::period_seconds)]
    pub frame_period: Option<f64>,
}

impl AxesArg {
    /// How files are read with these options (and `--lenient` as given).
    pub fn read_options(&self, lenient: bool) -> ReadOptions {
        let (axes, topic) = (self.axes, self.topic.clone());
        ReadOptions {
            lenient,
            axes,
            topic,
        }
    }
}

impl StanceArgs {
    /// The detector's settings these options give (the defaults for those not given), checked to fit
    /// together.
    pub fn segment_params(&self) -> anyhow::Result<ValidSegmentParams> {
        let default = SegmentParams::default();
        let params = SegmentParams {
            baseline: self.stance_baseline,
            on_fraction: self.stance_threshold.unwrap_or(default.on_fraction),
            off_fraction: self.stance_hysteresis.unwrap_or(default.off_fraction),
            min_stance_frames: self.stance_min_frames.unwrap_or(default.min_stance_frames),
            max_stance_frames: self.stance_max_frames,
            // A gap of N unloaded frames ends a stance: dropouts of up to N - 1 are bridged.
            max_gap_frames: self
                .stance_min_gap
                .map_or(default.max_gap_frames, |gap| gap.saturating_sub(1)),
            ..default
        };
        params
            .check()
            .context("the --stance-* options do not fit together")
    }
}

impl SampleArgs {
    /// The sample options of the kind named; `--sample auto` is refused (it is for train, eval and
    /// report).
    pub fn options(&self) -> anyhow::Result<SampleOptions> {
        match self.choice()? {
            SampleChoice::Auto => anyhow::bail!(
                "--sample auto races one frame against the whole sample (presrs train, eval and \
                 report); name one here: frame, stance or series"
            ),
            SampleChoice::Kind(kind) => self.options_of(kind),
        }
    }

    /// Which frame of each stance is a one-frame sample (`--stance-frame`, mid when not given).
    pub fn stance_frame(&self) -> SampleFrame {
        self.stance_frame.unwrap_or_default()
    }

    /// Refuses, or warns of (on stderr), the sample options given that do nothing with the sample
    /// kind chosen ([`check_sample_settings`] says which and why); a refusal is a usage error of
    /// `subcommand`.
    pub fn check_settings(&self, subcommand: &'static str) -> anyhow::Result<()> {
        let given = GivenSampleSettings {
            stance_length: self.stance_length,
            stance_frame: self.stance_frame,
            series_axis: self.series_axis.as_deref(),
        };
        let warnings = check_sample_settings(self.sample, &given)
            .map_err(|err| UsageError::error(subcommand, err))?;
        for warning in &warnings {
            stderr_line!("warning: {warning}");
        }
        Ok(())
    }

    /// `--sample` with `--stance-length` and `--series-axis` applied to the kind named.
    pub fn choice(&self) -> anyhow::Result<SampleChoice> {
        let time_in_rows = self.series_axis.as_deref() == Some("rows");
        self.sample
            .with_settings(self.stance_length, time_in_rows)
            .map_err(anyhow::Error::msg)
    }

    /// The options, as frames with `--sample auto` (a race reads the frames first).
    pub fn options_or_frames(&self) -> anyhow::Result<SampleOptions> {
        self.options_of(self.choice()?.kind().unwrap_or(SampleKind::Frame))
    }

    /// The whole sample's settings for `--sample auto`.
    pub fn whole_sample(&self) -> presrs::train::sample_race::WholeSample {
        presrs::train::sample_race::WholeSample {
            stance_length: self.stance_length,
            time_in_rows: self.series_axis.as_deref() == Some("rows"),
        }
    }

    /// The options with the sample kind `kind` (the other settings as given).
    pub fn options_of(&self, kind: SampleKind) -> anyhow::Result<SampleOptions> {
        Ok(SampleOptions {
            kind,
            sample: self.stance_frame(),
            include_partial: self.include_partial,
            read: self.read_options(),
            dead_sensels: self.dead_sensels(),
            segment: self.stance.segment_params()?,
            one_sample_per_file: self.stance.one_sample_per_file,
            frame_period_s: self.stance.frame_period,
            decision_points: Vec::new(),
            skip_short_stances: false,
        })
    }

    /// The dead-sensel correction to apply (`None` with `--keep-dead-sensels`).
    pub fn dead_sensels(&self) -> Option<DeadSenselConfig> {
        (!self.keep_dead_sensels).then(DeadSenselConfig::default)
    }

    /// Reads one recording file, its dead sensels filled unless `--keep-dead-sensels` (noted in
    /// `fills`); its warnings go to stderr.
    pub fn read(&self, path: &Path, fills: &mut DeadSenselFills) -> anyhow::Result<Recording> {
        let (parsed, filled) =
            read_corrected(path, &self.read_options(), self.dead_sensels().as_ref())?;
        for warning in &parsed.warnings {
            stderr_line!("warning: {warning}");
        }
        fills.add(path.to_path_buf(), filled);
        Ok(parsed.recording)
    }

    pub fn read_options(&self) -> ReadOptions {
        self.axes.read_options(self.lenient)
    }
}

/// `--sample`: one of [`SampleChoice::NAMES`] (a bad value is a usage error listing them).
fn sample_choice_parser() -> impl clap::builder::TypedValueParser<Value = SampleChoice> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(SampleChoice::NAMES)
        .try_map(|name| name.parse::<SampleChoice>())
}

/// Reads a manifest and all its samples (a spinner meanwhile); warnings go to stderr.
pub fn load_manifest(path: &Path, samples: &SampleArgs) -> anyhow::Result<Dataset> {
    let dataset = Dataset::load(path, &samples.options()?, &TerminalProgress::default())?;
    print_load_warnings(&dataset);
    Ok(dataset)
}

/// A loaded data set's warnings and dead-sensel note, on stderr.
pub fn print_load_warnings(dataset: &Dataset) {
    for warning in &dataset.warnings {
        stderr_line!("warning: {warning}");
    }
    note_dead_sensels(&dataset.dead_sensels);
}

/// The one-line note on stderr of the dead sensels filled, if any.
pub fn note_dead_sensels(fills: &DeadSenselFills) {
    if let Some(summary) = fills.summary() {
        stderr_line!(
            "note: {summary} (from their neighbours; --keep-dead-sensels to use them as read)"
        );
    }
}

/// The library's progress on stderr: a bar (or a spinner for a task of unknown length) when stderr is a
/// terminal; otherwise (logs, CI) a `progress: ...` line every [`progress_interval`] while a task runs
/// ([`ProgressLines`]); warnings as `warning: ...` lines.
#[derive(Debug)]
pub struct TerminalProgress {
    bar: std::sync::Mutex<Option<ProgressBar>>,
    /// The task's progress lines when stderr is not a terminal.
    lines: ProgressLines,
}

impl Default for TerminalProgress {
    fn default() -> Self {
        let sink = std::sync::Arc::new(|line: &str| stderr_line!("progress: {line}"));
        Self {
            bar: std::sync::Mutex::default(),
            lines: ProgressLines::new(progress_interval(), sink),
        }
    }
}

impl TerminalProgress {
    fn bar(&self) -> std::sync::MutexGuard<'_, Option<ProgressBar>> {
        self.bar
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// `KIND: message` on stderr, above the bar if one is shown.
    fn line(&self, kind: &str, message: &str) {
        match self.bar().as_ref() {
            Some(bar) => bar.suspend(|| stderr_line!("{kind}: {message}")),
            None => stderr_line!("{kind}: {message}"),
        }
    }
}

impl Progress for TerminalProgress {
    fn start(&self, task: &str, total: Option<u64>) {
        if !std::io::stderr().is_terminal() {
            self.lines.start(task, total);
        }
        let bar = match total {
            Some(total) => progress_bar(total, task),
            None => spinner(task),
        };
        if let Some(old) = self.bar().replace(bar) {
            old.finish_and_clear();
        }
    }

    fn advance(&self, steps: u64) {
        if let Some(bar) = self.bar().as_ref() {
            bar.inc(steps);
        }
        self.lines.advance(steps);
    }

    fn finish(&self) {
        self.lines.finish();
        if let Some(bar) = self.bar().take() {
            bar.finish_and_clear();
        }
    }

    /// On a terminal the bar's message; otherwise a line at once (stages are few, and a log should
    /// say where the time went).
    fn stage(&self, stage: &str) {
        if std::io::stderr().is_terminal() {
            if let Some(bar) = self.bar().as_ref() {
                bar.set_message(stage.to_owned());
            }
        } else {
            stderr_line!("progress: {stage}");
        }
    }

    fn warn(&self, warning: &presrs::Warning) {
        self.line("warning", &warning.render(presrs::Face::Cli));
    }

    fn note(&self, message: &str) {
        self.line("note", message);
    }
}

/// A progress bar on stderr when it is a terminal; hidden otherwise (pipes, CI, logs).
pub fn progress_bar(len: u64, message: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len).with_message(message.to_owned());
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>20} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// A spinner on stderr when it is a terminal; hidden otherwise.
pub fn spinner(message: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let spinner = ProgressBar::new_spinner().with_message(message.to_owned());
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    spinner
}

/// Writes a JSON document followed by a newline.
pub fn write_json(
    out: &mut dyn std::io::Write,
    value: &impl serde::Serialize,
) -> anyhow::Result<()> {
    serde_json::to_writer_pretty(&mut *out, value).context("cannot write JSON")?;
    writeln!(out)?;
    Ok(())
}

fn parse_sample_frame(text: &str) -> Result<SampleFrame, String> {
    text.parse::<SampleFrame>().map_err(|err| err.to_string())
}

fn parse_baseline_mode(text: &str) -> Result<BaselineMode, String> {
    text.parse::<BaselineMode>().map_err(|err| err.to_string())
}

/// `--novelty on|off`: whether a model that scores novelty may decide `unknown`.
#[derive(Clone, Copy, Debug, clap::Args)]
pub struct NoveltyArgs {
    /// on (the default): a sample far from every trained class is decided `unknown`, the nearest class
    /// beside it (models trained before novelty scores existed have none and never do); off: every
    /// decision is one of the model's classes, as before.
    // `Set`: a `bool` field is otherwise a value-less flag, and `on`/`off` would be refused.
    #[arg(long, value_name = "on|off", default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub novelty: bool,
}

impl NoveltyArgs {
    /// `file` with its novelty score dropped when off.
    pub fn apply(
        self,
        mut file: presrs_io::model_file::ModelFile,
    ) -> presrs_io::model_file::ModelFile {
        if !self.novelty {
            file.model = file.model.without_novelty();
        }
        file
    }
}

fn parse_on_off(text: &str) -> Result<bool, String> {
    match text {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(format!("{other:?}: give on or off")),
    }
}
