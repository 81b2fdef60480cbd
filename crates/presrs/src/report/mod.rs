//! Report assembly: every figure of a data set (and a model, an evaluation, the simulation) in a
//! folder with an `index.html` that opens offline. [`report_dataset`] is `presrs report`;
//! [`write_simulation_report`] (a simulated data set and its evaluations) is what `reproduce` writes,
//! [`write_eval_report`] what `eval --report` writes. The figures themselves are `presrs-report`'s,
//! re-exported here.

mod dataset_report;
mod draws;
mod faults;
mod model_check;
mod options;
mod page;
mod provenance;
mod simulation;
mod sources;

pub use presrs_report::{
    EarlyCurve, Evaluation, FaultResult, Figure, Format, MovieOptions, PressureFigure,
    PressureGrid, PressureScale, ReportError, ReportInputs, ReportRecording, SimulationInputs,
    render_rgb, render_svg, save_figure, write_movie,
};

pub use dataset_report::{
    ReportSummary, report_dataset, report_eval_options, report_holdout, report_racing_samples,
};
pub use draws::shrink_draw;
pub use faults::{AUTO_METHOD, PAPER_METHOD, fault_sweep};
pub use options::ReportOptions;
pub use page::{write_early_report, write_eval_report, write_leave_class_out_report, write_report};
pub use provenance::provenance;
pub use simulation::{
    PAPER_TABLE2, SimulationReportData, train_report_model, write_simulation_report,
};

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use std::collections::BTreeMap;

    use presrs_core::evaluation::{Models, Protocol};
    use presrs_core::pipeline::LabeledImage;
    use presrs_core::split::{ValidationSize, stratified_split};
    use presrs_core::stance::{ValidSegmentParams, segment_recording};
    use presrs_core::{Frame, Grid};
    use presrs_sim::{DatasetSpec, SimConfig, simulate_dataset};

    use super::model_check::eval_samples;
    use super::*;
    use crate::dataset::Sample;
    use crate::method::Method;
    use crate::progress::Quiet;

    #[test]
    fn a_short_class_shrinks_the_whole_draw() {
        use ValidationSize::{Count, Fraction};
        assert_eq!(shrink_draw(30, 20, Count(7)), (20, Count(7)));
        assert_eq!(shrink_draw(6, 20, Count(7)), (6, Fraction(0.35)));
        assert_eq!(shrink_draw(6, 20, Count(5)), (6, Fraction(0.25)));
        assert_eq!(shrink_draw(6, 20, Fraction(0.3)), (6, Fraction(0.3)));
        // every image asked for: a count stays a count
        assert_eq!(shrink_draw(6, usize::MAX, Count(2)), (6, Count(2)));
        // the scaled draw splits: 6 picked give 2 for validation, 4 for training
        let labels = [["carpet"; 6], ["wood"; 6]].concat();
        let (per_class, validation) = shrink_draw(6, 20, Count(7));
        let split = stratified_split(&labels, Some(per_class), validation, 1).unwrap();
        assert_eq!((split.train.len(), split.validation.len()), (8, 4));
    }

    /// The entry point `reproduce` calls, on a small simulated data set.
    #[test]
    fn simulation_report_has_table1_and_the_hopper() {
        let config = SimConfig::default();
        let mut spec = DatasetSpec::paper(3);
        spec.hops_per_gait = Some(30);
        let dataset = simulate_dataset(&config, &spec).unwrap();
        let mut frames = Vec::new();
        for trial in &dataset.trials {
            let segmentation =
                segment_recording(&trial.recording, &ValidSegmentParams::default()).unwrap();
            for stance in segmentation.complete() {
                frames.push((
                    trial
                        .recording
                        .frame(stance.mid_frame())
                        .unwrap()
                        .to_frame(),
                    trial.plan.terrain.clone(),
                    trial.plan.gait.name.clone(),
                ));
            }
        }
        let samples: Vec<LabeledImage<'_>> = frames
            .iter()
            .map(|(f, t, g)| LabeledImage {
                frame: f.view(),
                label: t,
                condition: Some(g),
                group: None,
            })
            .collect();
        let protocol = Protocol::TrainCondition {
            condition: Some("G2".into()),
            per_class: Some(15),
            validation: ValidationSize::Count(5),
        };
        let config_train = presrs_core::pipeline::TrainConfig::default()
            .check()
            .unwrap();
        let report = presrs_core::evaluation::Evaluation {
            samples: &samples,
            protocol: &protocol,
            repeats: 2,
            seed: 1,
            progress: &|| {},
        }
        .run(Models::Config(&config_train))
        .unwrap();
        let evaluations = BTreeMap::from([("G2".to_owned(), report)]);
        let dir = tempfile::tempdir().unwrap();
        let index = write_simulation_report(
            &SimulationReportData::from_dataset(&dataset).unwrap(),
            &config,
            &evaluations,
            1,
            dir.path(),
        )
        .unwrap();
        let html = std::fs::read_to_string(index).unwrap();
        for needle in [
            "table1_velocity.png",
            "hopper.png",
            "confusion.png",
            "paper",
        ] {
            assert!(html.contains(needle), "{needle}");
        }
        for part in html.split("src=\"").skip(1) {
            let name = &part[..part.find('"').unwrap()];
            assert!(dir.path().join(name).is_file(), "{name}");
        }
    }

    /// The fault chart's numbers are those of `Evaluation::run_each`, and the report shows them.
    #[test]
    fn fault_sweep_numbers_come_from_the_evaluation_engine() {
        use presrs_core::classifier::ClassifierKind;
        use presrs_core::features::FeatureKind;
        use presrs_core::perturb::Perturbation;
        use presrs_core::synthetic::{SYNTHETIC_CLASSES, synthetic_frame};
        use rand::SeedableRng;

        use crate::method::{ClassifierChoice, FeatureChoice};

        // The report's options with `features`, `classifier` and the test's draw.
        let parse = |features: FeatureChoice, classifier: ClassifierKind| ReportOptions {
            per_class: 10,
            validation: ValidationSize::Count(3),
            fault_repeats: 2,
            method: Method {
                features,
                classifier: ClassifierChoice::Kind(classifier),
                dims: Some(20),
                ..Method::default()
            },
            ..ReportOptions::default()
        };
        let args = parse(
            FeatureChoice::Kinds(vec![FeatureKind::FFT1D]),
            ClassifierKind::PWE,
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let frames: Vec<(Frame, &str, &str)> = (0..96)
            .map(|i| {
                (
                    synthetic_frame(i % 4, &mut rng),
                    SYNTHETIC_CLASSES[i % 4],
                    ["G1", "G2", "G3"][(i / 4) % 3],
                )
            })
            .collect();
        let triples: Vec<(&Frame, &str, Option<&str>)> =
            frames.iter().map(|(f, l, c)| (f, *l, Some(*c))).collect();
        let config = args.method.train_config(Grid::new(44, 44)).unwrap();
        let samples = eval_samples(&triples);
        let protocol = Protocol::TrainCondition {
            condition: Some("G2".into()),
            per_class: Some(8), // 8 images per class of G2: fewer than --per-class 10
            validation: ValidationSize::Fraction(0.3), // --validation 3 of 10, scaled
        };
        let (faults, note) = fault_sweep(&args, &samples, &protocol, &config, &Quiet).unwrap();
        assert!(note.contains("2 repeat(s)"), "{note}");
        // The evaluation's 5 repeats against the sweep's 2: the page says why their figures differ.
        assert_eq!(args.repeats, 5);
        assert!(
            note.contains("averages these 2 repeat(s), where the evaluation above averages 5"),
            "{note}"
        );
        // Leaving one of 3 groups out: the progress announces the steps it takes (was 2 of 6).
        let grouped: Vec<LabeledImage<'_>> = samples
            .iter()
            .map(|s| LabeledImage {
                group: s.condition,
                ..*s
            })
            .collect();
        let by_group = Protocol::LeaveOneOut {
            column: "group".into(),
            per_class: Some(8),
            validation: ValidationSize::Fraction(0.3),
        };
        let recorder = crate::progress::Recorder::default();
        fault_sweep(&args, &grouped, &by_group, &config, &recorder).unwrap();
        let log = recorder.log();
        assert_eq!(log.tasks, [("fault sweep".to_owned(), Some(log.steps))]);
        assert_eq!(log.steps, 3 * 2, "3 groups x 2 repeats");
        assert!(
            note.starts_with("trained on G2 (8 images per class)"),
            "{note}"
        );
        let sweep = Perturbation::default_sweep();
        assert_eq!(
            faults.len(),
            1 + sweep.len(),
            "one method, the clean run and every level"
        );

        let dead = Perturbation::Dead(0.1);
        let transform = |i: usize, frame: presrs_core::FrameView<'_>, seed: u64| {
            Ok(dead.apply(frame, seed, i as u64))
        };
        let evaluation = presrs_core::evaluation::Evaluation {
            samples: &samples,
            protocol: &protocol,
            repeats: 2,
            seed: 1,
            progress: &|| {},
        };
        let direct = evaluation
            .run_each(Models::Config(&config), &[Some(&transform)])
            .unwrap()
            .reports
            .remove(0);
        let swept = faults
            .iter()
            .find(|f| f.perturbation == Some(dead))
            .unwrap();
        assert_eq!(swept.accuracy, direct.overall);
        let clean = evaluation.run(Models::Config(&config)).unwrap();
        assert_eq!(
            faults
                .iter()
                .find(|f| f.perturbation.is_none())
                .unwrap()
                .accuracy,
            clean.overall
        );

        // With the features automatic and the classifier fixed (mle), the line labelled the paper's
        // method is the paper's method: the numbers of the explicit fft1d + pwe run above (it was the
        // configured fft1d + mle).
        let mle_args = parse(FeatureChoice::Auto, ClassifierKind::MLE);
        let mle_config = mle_args.method.train_config(Grid::new(44, 44)).unwrap();
        let (auto_faults, _) =
            fault_sweep(&mle_args, &samples, &protocol, &mle_config, &Quiet).unwrap();
        let paper: Vec<_> = auto_faults
            .iter()
            .filter(|f| f.method == PAPER_METHOD)
            .map(|f| (f.perturbation, f.accuracy))
            .collect();
        let explicit: Vec<_> = faults
            .iter()
            .map(|f| (f.perturbation, f.accuracy))
            .collect();
        assert_eq!(paper, explicit);
        assert!(auto_faults.iter().any(|f| f.method == AUTO_METHOD));

        // The report draws them and tabulates the same numbers.
        let report_samples: Vec<Sample> = frames
            .iter()
            .map(|(f, l, c)| {
                let mut sample = Sample::new(f.clone(), *l, "synthetic".into(), 0);
                sample.condition = Some((*c).to_owned());
                sample
            })
            .collect();
        let mut inputs = ReportInputs::new("faults", &report_samples);
        inputs.faults = faults.clone();
        inputs.fault_note = Some(note);
        let dir = tempfile::tempdir().unwrap();
        let index = write_report(&inputs, dir.path()).unwrap();
        let html = std::fs::read_to_string(index).unwrap();
        assert!(html.contains("src=\"fault_sweep.png\""));
        assert!(dir.path().join("fault_sweep.png").is_file());
        let row = html.split("<tr><td>dead=0.1</td>").nth(1).unwrap();
        let expected = format!(
            "<td>{:.1} % ± {:.1}</td>",
            100.0 * direct.overall.mean,
            100.0 * direct.overall.std
        );
        assert!(row.starts_with(&expected), "{expected} vs {}", &row[..60]);
    }
}
