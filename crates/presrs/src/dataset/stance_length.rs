//! Whole-stance samples laid into one length, and the check that a length asked for suits the stances.

use presrs_core::Sample;
use presrs_core::stance::summary::pad_to;
use presrs_io::IoError;
use presrs_io::message::{Message, Opt, Warning};

/// How many times the longest stance a `stance length` may be: beyond it a sample is mostly the zeros
/// after lift-off (features of padding), and a length typed with a few digits too many would take all
/// the memory there is (12 channels x 100 000 000 frames is 9.6 GB a sample).
pub const MAX_STANCE_LENGTH_PER_LONGEST: usize = 4;

/// Lays every whole-stance sample into one length: `length`, or the longest stance's. The warning, when
/// some were longer, says how many were cut to their first `length` frames. A `length` over
/// [`MAX_STANCE_LENGTH_PER_LONGEST`] times the longest stance is refused before anything is
/// allocated ([`check_stance_length`]); `name` (the manifest or the arrays) names the data in the error.
pub fn pad_stance_samples(
    name: &str,
    samples: &mut [Sample],
    length: Option<usize>,
) -> std::result::Result<Option<Warning>, IoError> {
    let longest = samples
        .iter()
        .map(|s| s.frame.grid().cols)
        .max()
        .unwrap_or(0);
    if let Some(length) = length {
        check_stance_length(name, length, longest)?;
    }
    let length = length.unwrap_or(longest);
    let mut cut = 0;
    for sample in samples.iter_mut() {
        let (padded, was_cut) = pad_to(&sample.frame.view(), length)
            .map_err(|err| IoError::format(name, err.to_string()))?;
        sample.frame = padded;
        cut += usize::from(was_cut);
    }
    Ok((cut > 0).then(|| {
        Warning::from(Message::from(format!(
            "{cut} of {} stances are longer than {length} frames: their first {length} frames are \
             used (the longest has {longest})",
            samples.len()
        )))
    }))
}

/// An error unless a stance length of `length` frames suits stances whose longest has `longest`
/// frames: at most [`MAX_STANCE_LENGTH_PER_LONGEST`] times it. The error says the longest stance
/// found and what to give (a stance length in the face's words: `--stance-length`, `stance_length=`).
pub fn check_stance_length(
    name: &str,
    length: usize,
    longest: usize,
) -> std::result::Result<(), IoError> {
    let most = longest.saturating_mul(MAX_STANCE_LENGTH_PER_LONGEST);
    if longest == 0 || length <= most {
        return Ok(());
    }
    Err(IoError::format(
        name,
        Message::new()
            .opt_is(Opt::StanceLength, length)
            .text(format!(
                " is far longer than the longest stance found ({longest} frames): every stance would \
                 be mostly zeros after lift-off; give at most {most} frames \
                 ({MAX_STANCE_LENGTH_PER_LONGEST} x the longest), or leave "
            ))
            .opt(Opt::StanceLength)
            .text(format!(" out to lay each stance into the longest's {longest} frames")),
    ))
}
