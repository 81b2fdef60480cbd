//! `results.md`: the reproduction's results as Markdown tables.

use std::io::Write;

use presrs_core::evaluation::MeanStd;

use crate::eval::calibration_line;
use crate::report::PAPER_TABLE2;

use super::results::{ComparisonSummary, Draw, LoadCheck, Results};

/// `results.md`: Tables I and II beside the paper's, the gait matrix, load independence, the other
/// methods and the segmentation check.
pub(super) fn write_markdown(
    results: &Results,
    table1: &str,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    writeln!(
        w,
        "# presrs reproduce (seed {}, {} repeats)\n",
        results.seed, results.repeats
    )?;
    writeln!(w, "## Table I: forward velocity\n\n```\n{table1}```\n")?;
    write_table2_markdown(results, w)?;
    write_matrix_markdown(results, w)?;
    if let Some(l) = &results.load_independence {
        write_load_markdown(l, w)?;
    }
    if !results.comparison.is_empty() {
        write_comparison_markdown(&results.comparison, results.draw, w)?;
    }
    let s = &results.segmentation;
    writeln!(
        w,
        "\nSegmentation against the simulator's truth: {} of {} stances within one frame ({} found), {} \
         with the same mid-stance frame.",
        s.matched_within_one_frame, s.true_hops, s.found_stances, s.same_mid_frame
    )
}

/// Table II beside the paper's, the classification time and the calibration.
fn write_table2_markdown(results: &Results, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        w,
        "## Table II: classification accuracy, trained on G2 ({} images per terrain, {} of them \
         validating)\n",
        results.draw.per_class, results.draw.validation
    )?;
    writeln!(
        w,
        "| tested | simulated (mean ± std) | paper |\n| --- | --- | --- |"
    )?;
    for (name, paper) in PAPER_TABLE2 {
        if let (Some(mean), Some(std)) = (results.table2.get(name), results.table2_std.get(name)) {
            writeln!(
                w,
                "| {name} | {:.1} % ± {:.1} | {:.1} % |",
                100.0 * mean,
                100.0 * std,
                100.0 * paper
            )?;
        }
    }
    writeln!(
        w,
        "\nMedian classification time: {:.2} µs per image (paper: 245 µs on a 2.67 GHz Core 2 Duo).\n",
        results.median_classify_ns as f64 / 1e3
    )?;
    if let Some(line) = results
        .evaluations
        .get("G2")
        .and_then(|g2| calibration_line(&g2.reliability))
    {
        writeln!(w, "Reported {line}.\n")?;
    }
    Ok(())
}

/// The accuracy of every training gait on every tested gait.
fn write_matrix_markdown(results: &Results, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "## Train gait × test gait accuracy\n")?;
    let gaits: Vec<&String> = results.images_per_gait.keys().collect();
    write!(w, "| train |")?;
    for gait in &gaits {
        write!(w, " {gait} |")?;
    }
    writeln!(w, " overall |")?;
    writeln!(w, "|{}", " --- |".repeat(gaits.len() + 2))?;
    for (train, row) in &results.train_test_matrix {
        write!(w, "| {train} |")?;
        for gait in gaits.iter().map(|g| g.as_str()).chain(["overall"]) {
            write!(
                w,
                " {:.1} % |",
                100.0 * row.get(gait).copied().unwrap_or(f64::NAN)
            )?;
        }
        writeln!(w)?;
    }
    Ok(())
}

/// The load-independence test: as recorded, scaled by the load ratio, and with `--normalise-load`.
fn write_load_markdown(l: &LoadCheck, w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        w,
        "\n## Load independence\n\nTrained on G2 at {:.2} kg; tested on every gait at {:.2} kg ({} images): \
         {:.1} % ± {:.1} as recorded, {:.1} % ± {:.1} scaled by the load ratio (the load known), {:.1} % ± \
         {:.1} with `--normalise-load` (trained and tested on images divided by their total load; the load \
         unknown).",
        l.nominal_load_kg,
        l.test_load_kg,
        l.test_images,
        100.0 * l.accuracy_unscaled.mean,
        100.0 * l.accuracy_unscaled.std,
        100.0 * l.accuracy_scaled.mean,
        100.0 * l.accuracy_scaled.std,
        100.0 * l.accuracy_normalised.mean,
        100.0 * l.accuracy_normalised.std
    )
}

/// The comparison as a Markdown table: accuracy per tested gait and overall, training and classification
/// time.
fn write_comparison_markdown(
    rows: &[ComparisonSummary],
    draw: Draw,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let mut gaits: Vec<&String> = rows.iter().flat_map(|r| r.per_gait.keys()).collect();
    gaits.sort();
    gaits.dedup();
    writeln!(
        w,
        "\n## Other methods\n\nEvery feature family × classifier, trained on G2 ({} images per terrain, {} of \
         them validating), tested on every other image, with the same draws as Table II (mean ± std over \
         the repeats). The paper's method is fft1d + pwe.\n",
        draw.per_class, draw.validation
    )?;
    write!(w, "| features | classifier |")?;
    for gait in &gaits {
        write!(w, " {gait} |")?;
    }
    writeln!(w, " overall | train ms | classify µs |")?;
    writeln!(w, "|{}", " --- |".repeat(gaits.len() + 5))?;
    let cell = |m: &MeanStd| format!("{:.1} ± {:.1}", 100.0 * m.mean, 100.0 * m.std);
    for row in rows {
        write!(w, "| {} | {} |", row.features, row.classifier)?;
        match (&row.overall, &row.error) {
            (Some(overall), _) => {
                for gait in &gaits {
                    write!(
                        w,
                        " {} |",
                        row.per_gait.get(*gait).map_or_else(|| "-".to_owned(), cell)
                    )?;
                }
                writeln!(
                    w,
                    " {} | {:.1} | {:.1} |",
                    cell(overall),
                    row.train_ms.mean,
                    row.median_classify_ns as f64 / 1e3
                )?;
            }
            (None, error) => {
                for _ in &gaits {
                    write!(w, " - |")?;
                }
                writeln!(
                    w,
                    " failed: {} | | |",
                    error.as_deref().unwrap_or("unknown error")
                )?;
            }
        }
    }
    Ok(())
}
