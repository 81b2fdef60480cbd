//! What `presrs inspect` prints (without --json): what a recording file holds, one line a field, then
//! the stance phases found, one row each.

use std::io::Write;

use presrs::inspect::InspectReport;
use presrs_core::stance::BaselineMode;

/// The table: the file (its topics), the sensor, the dead sensels, the frames and load, the warnings,
/// then the stances.
pub fn print_inspect_table(report: &InspectReport, out: &mut dyn Write) -> anyhow::Result<()> {
    writeln!(out, "file           {}", report.file)?;
    print_topics(report, out)?;
    print_sensor(report, out)?;
    print_dead_sensels(report, out)?;
    let load_unit = print_frames_and_load(report, out)?;
    for warning in &report.warnings {
        writeln!(out, "warning        {warning}")?;
    }
    print_stances(report, &load_unit, out)
}

/// The topics of an MCAP bag, the described one marked.
fn print_topics(report: &InspectReport, out: &mut dyn Write) -> anyhow::Result<()> {
    for t in &report.topics {
        let mark = if report.topic.as_deref() == Some(t.topic.as_str()) {
            " (described below)"
        } else if t.frames {
            " (frames: --topic to describe it)"
        } else {
            ""
        };
        writeln!(
            out,
            "topic          {}  {}  {} messages{mark}",
            t.topic, t.schema, t.messages
        )?;
    }
    Ok(())
}

/// The sensor, its size and its pitch.
fn print_sensor(report: &InspectReport, out: &mut dyn Write) -> anyhow::Result<()> {
    let sensor = report
        .sensor
        .clone()
        .unwrap_or_else(|| "unknown".to_owned());
    writeln!(out, "sensor         {sensor}")?;
    writeln!(
        out,
        "size           {} rows x {} cols ({} absent sensels)",
        report.rows, report.cols, report.absent_sensels
    )?;
    let pitch = match (report.row_pitch_mm, report.col_pitch_mm) {
        (Some(r), Some(c)) => format!("{r} mm x {c} mm"),
        _ => "unknown".to_owned(),
    };
    writeln!(out, "pitch          {pitch}")?;
    Ok(())
}

/// The dead sensels (the first 20) and what is done with them; nothing when there are none.
fn print_dead_sensels(report: &InspectReport, out: &mut dyn Write) -> anyhow::Result<()> {
    if report.dead_sensels.is_empty() {
        return Ok(());
    }
    let at: Vec<String> = report
        .dead_sensels
        .iter()
        .take(20)
        .map(|d| format!("({}, {})", d.row, d.col))
        .collect();
    let more = report.dead_sensels.len().saturating_sub(at.len());
    writeln!(
        out,
        "dead sensels   {} at row, col (0-based) {}{}",
        report.dead_sensels.len(),
        at.join(" "),
        if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        }
    )?;
    writeln!(out, "               {}", report.dead_sensels_treatment())?;
    Ok(())
}

/// The frames, their period, the units and the load range; returns the unit of every load.
fn print_frames_and_load(report: &InspectReport, out: &mut dyn Write) -> anyhow::Result<String> {
    let period = report.frame_period_s.map_or_else(
        || "(frame period unknown)".to_owned(),
        |p| format!("at {p} s ({:.2} Hz)", 1.0 / p),
    );
    writeln!(out, "frames         {} {period}", report.frames)?;
    if report.units_stated {
        writeln!(out, "units          {}", report.units)?;
    } else {
        writeln!(
            out,
            "units          {} (assumed: the file states no unit)",
            report.units
        )?;
    }
    // The unit of every load below: the recording's unit summed over the sensels.
    let unit = if report.units == "raw" {
        "raw counts"
    } else {
        report.units.as_str()
    };
    let load_unit = format!("{unit} summed over sensels");
    writeln!(
        out,
        "total load     {} .. {} {load_unit} (baseline noise {:.3})",
        presrs::inspect::load_text(report.load_min),
        presrs::inspect::load_text(report.load_max),
        report.baseline_noise
    )?;
    if let (Some(min), Some(max)) = (report.force_min_n, report.force_max_n) {
        writeln!(
            out,
            "total force    {min:.1} .. {max:.1} N (pressure x sensel area, as plot --movie draws it)"
        )?;
    }
    Ok(load_unit)
}

/// The stances found, how they were measured, and one table row per stance.
fn print_stances(
    report: &InspectReport,
    load_unit: &str,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let complete = report.stances.iter().filter(|s| !s.partial).count();
    writeln!(
        out,
        "stances        {} found, {complete} complete, measured from the {}",
        report.stances.len(),
        match report.stance_mode {
            BaselineMode::Floor => "local floor (--stance-baseline floor)",
            BaselineMode::Contact =>
                "zero level: the recording is one contact (--stance-baseline contact)",
            BaselineMode::Auto | BaselineMode::Drifting => "baseline (--stance-baseline drifting)",
        }
    )?;
    if let Some(reason) = &report.stance_mode_reason {
        writeln!(out, "               chosen automatically: {reason}")?;
    }
    for note in &report.stance_notes {
        writeln!(out, "note           {note}")?;
    }
    if report.stances.is_empty() {
        return Ok(());
    }
    writeln!(out, "  (peak_load in {load_unit})")?;
    writeln!(out, "  #  start  len  peak_load  sample_frame  partial")?;
    for (i, stance) in report.stances.iter().enumerate() {
        writeln!(
            out,
            "{:>3}  {:>5}  {:>3}  {:>9.1}  {:>12}  {}",
            i,
            stance.start,
            stance.len,
            stance.peak_load,
            stance
                .sample_frame
                .map_or_else(|| "-".to_owned(), |f| f.to_string()),
            stance.partial_text(report.frames)
        )?;
    }
    Ok(())
}
