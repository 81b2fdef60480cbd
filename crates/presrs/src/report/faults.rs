//! The sensor-fault sweep of `presrs report`: accuracy against fault level, for the paper's method and
//! the automatic choice, with the evaluation's protocol and draws.

use std::fmt::Write as _;
use std::time::Instant;

use presrs_core::evaluation::{EvalReport, Models, Protocol};
use presrs_core::pipeline::{CheckedTrainConfig, LabeledImage};
use presrs_report::FaultResult;

use super::options::ReportOptions;
use crate::error::Result;
use crate::eval::{Holdout, run_counted};
use crate::progress::Progress;

/// The paper's method, as fault results name it.
pub const PAPER_METHOD: &str = "paper: fft1d + pwe";
/// The automatic choice of features and classifier, as fault results name it.
pub const AUTO_METHOD: &str = "automatic choice";

/// `presrs report`'s sensor-fault sweep: the evaluation's protocol and draws with every test image
/// perturbed at each level of
/// [`Perturbation::default_sweep`](presrs_core::perturb::Perturbation::default_sweep), for the configured
/// pipeline `config`, or with auto options for the paper's method (whatever the fixed part says) and the
/// automatic choice; each model is trained once per repeat and tested under every perturbation. Also
/// returns a note on how it was run.
pub fn fault_sweep(
    options: &ReportOptions,
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
    config: &CheckedTrainConfig,
    progress: &dyn Progress,
) -> Result<(Vec<FaultResult>, String)> {
    use presrs_core::evaluation::TestTransform;
    use presrs_core::perturb::Perturbation;
    let started = Instant::now();
    let sweep = Perturbation::default_sweep();
    let transforms: Vec<_> = sweep.iter().map(Perturbation::transform).collect();
    let mut each: Vec<Option<&TestTransform<'_>>> = vec![None];
    each.extend(transforms.iter().map(|t| Some(t as &TestTransform<'_>)));
    let auto = options.method.is_auto();
    let methods = 1 + usize::from(auto);
    let grid = samples[0].frame.grid();
    // Next to an automatic choice the paper's method; else the configured pipeline alone.
    let paper_config;
    let paper = if auto {
        paper_config = options.method.paper_config(grid)?;
        &paper_config
    } else {
        config
    };
    let candidates = if auto {
        options.method.candidates_for(
            grid,
            false,
            &options.samples.kind,
            crate::method::race_draws_for(samples.len()),
        )?
    } else {
        Vec::new()
    };
    progress.note(&format!(
        "fault sweep: {} perturbations x {methods} method(s) x {} repeat(s) (--fault-repeats 0 skips it)",
        sweep.len(),
        options.fault_repeats
    ));
    let (paper_reports, auto_reports) = run_counted(
        samples,
        protocol,
        (options.fault_repeats, options.seed),
        (
            "fault sweep",
            (methods * protocol.models_per_repeat(samples) * options.fault_repeats) as u64,
        ),
        progress,
        |evaluation| {
            let paper = evaluation.run_each(Models::Config(paper), &each)?.reports;
            let auto = if auto {
                evaluation
                    .run_each(Models::Auto(options.method.auto_choice(&candidates)), &each)?
                    .reports
            } else {
                Vec::new()
            };
            Ok((paper, auto))
        },
    )?;
    let paper_name = if auto {
        PAPER_METHOD.to_owned()
    } else {
        let c = paper.config();
        format!("{} + {}", c.features.name(), c.classifier.kind().as_str())
    };
    let mut results = sweep_fault_results(&paper_name, paper_reports, &sweep);
    if auto {
        results.extend(sweep_fault_results(AUTO_METHOD, auto_reports, &sweep));
    }
    let seconds = started.elapsed().as_secs_f64();
    progress.note(&format!("fault sweep: {seconds:.1} s"));
    Ok((results, fault_sweep_note(options, protocol, seconds)))
}

/// The fault sweep's results of `method`, one per report: the first without a perturbation, then one
/// per level of `sweep`.
fn sweep_fault_results(
    method: &str,
    reports: Vec<EvalReport>,
    sweep: &[presrs_core::perturb::Perturbation],
) -> Vec<FaultResult> {
    reports
        .into_iter()
        .enumerate()
        .map(|(k, report)| FaultResult {
            perturbation: k.checked_sub(1).map(|k| sweep[k]),
            method: method.to_owned(),
            accuracy: report.overall,
        })
        .collect()
}

/// How the sweep was run: the protocol, the draw, the repeats, the seed and how long it took.
fn fault_sweep_note(options: &ReportOptions, protocol: &Protocol, seconds: f64) -> String {
    let per_class = match protocol {
        Protocol::TrainCondition { per_class, .. } | Protocol::LeaveOneOut { per_class, .. } => {
            per_class.map_or_else(
                || "every image".to_owned(),
                |n| format!("{n} images per class"),
            )
        }
    };
    let mut note = format!(
        "{} ({per_class}), {} repeat(s), seed {}; the sweep took {seconds:.1} s.",
        protocol_words(protocol),
        options.fault_repeats,
        options.seed
    );
    if options.repeats > 0 && options.repeats != options.fault_repeats {
        let _ = write!(
            note,
            " Its clean accuracy (as recorded) averages these {} repeat(s), where the evaluation \
             above averages {} with the same protocol and seeds from {}: the two figures differ by \
             the draws they cover, not by what was measured.",
            options.fault_repeats, options.repeats, options.seed
        );
    }
    note
}

/// The words for `protocol`: `trained on G2`, `leave one group out`, `random draw`.
fn protocol_words(protocol: &Protocol) -> String {
    match protocol {
        Protocol::TrainCondition { condition, .. } => {
            Holdout::TrainCondition(condition.clone()).describe()
        }
        Protocol::LeaveOneOut { column, .. } => Holdout::LeaveOneOut(column.clone()).describe(),
    }
}
