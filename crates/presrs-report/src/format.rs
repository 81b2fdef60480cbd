//! Number formatting shared by the charts and the heat maps; a leaf module (it imports nothing from
//! the crate) so that neither has to import the other for it.

/// A tick label: integers without a decimal point, others with up to three decimals.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if a < 1e-12 {
        return "0".to_owned();
    }
    if (v - v.round()).abs() < 1e-9 * a.max(1.0) && a < 1e9 {
        return format!("{v:.0}");
    }
    if !(1e-3..1e9).contains(&a) {
        return format!("{v:.1e}");
    }
    let text = format!("{v:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_owned()
}
