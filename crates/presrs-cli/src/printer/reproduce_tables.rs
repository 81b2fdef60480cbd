//! What `presrs reproduce` prints of the paper's experiment: Tables I and II next to the paper's, the
//! train x test gait matrix, the load-independence test and the other methods.

use std::io::Write;

use presrs::eval::calibration_line;
use presrs::report::PAPER_TABLE2;
use presrs::reproduce::{PAPER_CLASSIFY_NS, Reproduction};

use super::eval_tables::comparison_table;

/// Where the data set came from, Table I, the stance images, Table II and the train x test matrix.
pub fn print_tables(reproduction: &Reproduction, out: &mut dyn Write) -> anyhow::Result<()> {
    let results = &reproduction.results;
    if let Some(main) = results.datasets.get("main") {
        writeln!(out, "{}", main.note)?;
    }
    writeln!(out, "Table I (simulated vs paper)")?;
    writeln!(out, "{}", reproduction.table1_text)?;
    let segmentation = &results.segmentation;
    writeln!(
        out,
        "{} stance images ({}); segmentation found {} of {} simulated stances within one frame, {} with the \
         same mid-stance frame",
        results.images_per_gait.values().sum::<usize>(),
        results
            .images_per_gait
            .iter()
            .map(|(g, n)| format!("{g}: {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        segmentation.matched_within_one_frame,
        segmentation.true_hops,
        segmentation.same_mid_frame
    )?;
    writeln!(
        out,
        "\nTable II (trained on G2, {} images per terrain; mean +- std over {} repeats)",
        results.draw.per_class, results.repeats
    )?;
    writeln!(out, "{:<10} {:>18} {:>8}", "tested", "simulated", "paper")?;
    for (name, paper) in PAPER_TABLE2 {
        if let (Some(mean), Some(std)) = (results.table2.get(name), results.table2_std.get(name)) {
            writeln!(
                out,
                "{:<10} {:>9.1} % +- {:<4.1} {:>6.1} %",
                name,
                100.0 * mean,
                100.0 * std,
                100.0 * paper
            )?;
        }
    }
    writeln!(
        out,
        "median classification time {:.2} us per image (paper: {:.0} us on a 2.67 GHz Core 2 Duo)",
        results.median_classify_ns as f64 / 1e3,
        PAPER_CLASSIFY_NS as f64 / 1e3
    )?;
    if let Some(line) = results
        .evaluations
        .get("G2")
        .and_then(|main| calibration_line(&main.reliability))
    {
        writeln!(out, "{line}")?;
    }
    let gaits: Vec<&String> = results.images_per_gait.keys().collect();
    writeln!(out, "\nTrain gait x test gait accuracy (%)")?;
    write!(out, "{:<8}", "train")?;
    for gait in &gaits {
        write!(out, " {gait:>7}")?;
    }
    writeln!(out, " {:>8}", "overall")?;
    for (train_gait, row) in &results.train_test_matrix {
        write!(out, "{train_gait:<8}")?;
        for gait in &gaits {
            let value = row.get(*gait).copied().unwrap_or(f64::NAN);
            write!(out, " {:>7.1}", 100.0 * value)?;
        }
        let overall = row.get("overall").copied().unwrap_or(f64::NAN);
        writeln!(out, " {:>8.1}", 100.0 * overall)?;
    }
    Ok(())
}

/// The load-independence test and the comparison of the other methods.
pub fn print_load_and_methods(
    reproduction: &Reproduction,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let results = &reproduction.results;
    if let Some(note) = &reproduction.load_dataset_note {
        writeln!(out, "{note}")?;
    }
    if let Some(err) = &reproduction.load_error {
        writeln!(out, "\nLoad independence: not measured: {err}")?;
    }
    if let Some(load_check) = &results.load_independence {
        writeln!(
            out,
            "\nLoad independence (trained on G2 at {:.2} kg, tested on all gaits at {:.2} kg, {} images)",
            load_check.nominal_load_kg, load_check.test_load_kg, load_check.test_images
        )?;
        writeln!(
            out,
            "  as recorded        {:5.1} % +- {:.1}\n  scaled by load     {:5.1} % +- {:.1}  (the paper: \
             the load is known)\n  normalised         {:5.1} % +- {:.1}  (--normalise-load: trained and \
             tested on images divided by their total, the load unknown)",
            100.0 * load_check.accuracy_unscaled.mean,
            100.0 * load_check.accuracy_unscaled.std,
            100.0 * load_check.accuracy_scaled.mean,
            100.0 * load_check.accuracy_scaled.std,
            100.0 * load_check.accuracy_normalised.mean,
            100.0 * load_check.accuracy_normalised.std
        )?;
    }
    if !reproduction.comparison.is_empty() {
        writeln!(
            out,
            "\nOther methods (trained on G2, {} images per terrain, the same draws as Table II; the paper's \
             is fft1d + pwe)",
            results.draw.per_class
        )?;
        write!(out, "{}", comparison_table(&reproduction.comparison))?;
    }
    Ok(())
}
