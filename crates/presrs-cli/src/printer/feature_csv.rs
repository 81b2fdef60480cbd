//! What `presrs features` prints: CSV with a header `frame,` and the features' names, then one row per
//! frame (its index, then its feature vector).

use std::fmt::Write;

/// The header line: `frame,` then the features' names.
pub fn header(names: &[String]) -> String {
    format!("frame,{}", names.join(","))
}

/// One frame's line: its index, then its features.
pub fn row(index: usize, features: &[f64]) -> String {
    let mut line = index.to_string();
    for value in features {
        let _ = write!(line, ",{value}");
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_names_every_column_and_a_row_starts_with_its_frame() {
        let names = ["fft1d_bin0".to_owned(), "fft1d_bin1".to_owned()];
        assert_eq!(header(&names), "frame,fft1d_bin0,fft1d_bin1");
        assert_eq!(row(40, &[1.5, 0.25]), "40,1.5,0.25");
    }
}
