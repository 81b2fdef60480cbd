//! Line kinds both the header and the frames recognise, and error-message helpers. A leaf module.

/// `ASCII_DATA` (or `ASCII_DATA:`), the key that ends the header.
pub(super) fn is_ascii_data(token: &str) -> bool {
    token.trim_end_matches(':') == "ASCII_DATA"
}

/// `Frame 12, timestamp 728` -> `(12, Some(", timestamp 728"))`; `None` if the line is not a frame line.
/// `Some(Err(..))` if it starts with `Frame ` but the number is malformed.
pub(super) fn frame_line(line: &str) -> Option<Result<(i64, Option<&str>), String>> {
    let head = line.get(..5)?;
    if !head.eq_ignore_ascii_case("frame") {
        return None;
    }
    let rest = &line[5..];
    if !rest.starts_with(|c: char| c.is_whitespace()) {
        return None;
    }
    let rest = rest.trim_start();
    let digits_end = rest
        .char_indices()
        .find(|&(i, c)| !(c.is_ascii_digit() || (i == 0 && (c == '-' || c == '+'))))
        .map_or(rest.len(), |(i, _)| i);
    let number = &rest[..digits_end];
    let suffix = &rest[digits_end..];
    Some(
        number
            .parse::<i64>()
            .map(|n| (n, (!suffix.is_empty()).then_some(suffix)))
            .map_err(|_| format!("expected a frame number after `Frame`, found `{}`", rest)),
    )
}

/// A cell or line shortened for an error message.
pub(super) fn clip(text: &str) -> String {
    const MAX: usize = 40;
    if text.chars().count() <= MAX {
        text.to_owned()
    } else {
        let head: String = text.chars().take(MAX).collect();
        format!("{head}...")
    }
}
