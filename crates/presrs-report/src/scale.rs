//! How a sensor's values and positions are shown (unit, factor, pitch). A leaf module: the heat maps
//! and the charts (load curves) both use it, and it imports nothing from the crate.

use presrs_core::{PressureUnit, SensorMeta};

/// How a sensor's values and positions are shown: the value unit (kPa when the recording's unit is a
/// known pressure unit, the recording's own unit otherwise) and the sensel pitch.
#[derive(Clone, Debug, PartialEq)]
pub struct PressureScale {
    /// Unit of the shown values, e.g. `kPa` or `raw counts`.
    pub unit: String,
    /// Shown value = stored value x `factor`.
    pub factor: f64,
    /// Sensel pitch between rows and between columns, mm (`None`: unknown; sensels are then drawn
    /// square and positions are in sensels).
    pub row_pitch_mm: Option<f64>,
    pub col_pitch_mm: Option<f64>,
}

impl Default for PressureScale {
    fn default() -> Self {
        Self::from_meta(None)
    }
}

impl PressureScale {
    /// The scale of a recording with this metadata (raw counts and square sensels when unknown).
    pub fn from_meta(meta: Option<&SensorMeta>) -> Self {
        let Some(meta) = meta else {
            return Self {
                unit: "raw counts".into(),
                factor: 1.0,
                row_pitch_mm: None,
                col_pitch_mm: None,
            };
        };
        let units = meta.units_or_raw();
        let (unit, factor) = match (units, units.kpa_per_unit()) {
            (_, Some(factor)) => ("kPa".to_owned(), factor),
            (PressureUnit::Raw, None) => ("raw counts".to_owned(), 1.0),
            (other, None) => (other.as_tekscan().to_owned(), 1.0),
        };
        let valid = |p: Option<f64>| p.filter(|p| p.is_finite() && *p > 0.0);
        let (row, col) = (valid(meta.row_pitch_mm), valid(meta.col_pitch_mm));
        Self {
            unit,
            factor,
            // One known pitch stands for both (square sensels are the rule).
            row_pitch_mm: row.or(col),
            col_pitch_mm: col.or(row),
        }
    }

    /// Whether positions are in millimetres (else in sensels).
    pub fn physical(&self) -> bool {
        self.row_pitch_mm.is_some() && self.col_pitch_mm.is_some()
    }

    /// `(row pitch, column pitch)` in the position unit.
    pub fn pitches(&self) -> (f64, f64) {
        match (self.row_pitch_mm, self.col_pitch_mm) {
            (Some(r), Some(c)) => (r, c),
            _ => (1.0, 1.0),
        }
    }

    /// `mm` or `sensels`.
    pub fn position_unit(&self) -> &'static str {
        if self.physical() { "mm" } else { "sensels" }
    }

    /// Axis label and factor for the total load of a frame (sum of stored values): force in newtons when
    /// the pressure unit and the sensel area are known, else the plain sum.
    pub fn load_axis(&self) -> (String, f64) {
        match self.newtons_per_unit() {
            Some(factor) => ("total force (N)".to_owned(), factor),
            None => (format!("total load (sum of {})", self.unit), self.factor),
        }
    }

    /// Newtons per stored value summed over sensels, when the pressure unit and the sensel area are
    /// known (a frame's total load times it is the force on the sensor).
    pub fn newtons_per_unit(&self) -> Option<f64> {
        match (self.unit.as_str(), self.row_pitch_mm, self.col_pitch_mm) {
            // kPa x mm² = 1e3 N/m² x 1e-6 m² = 1e-3 N.
            ("kPa", Some(r), Some(c)) => Some(self.factor * r * c * 1e-3),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_uses_kpa_and_pitch_and_falls_back_to_counts() {
        let meta = SensorMeta {
            row_pitch_mm: Some(5.08),
            col_pitch_mm: Some(5.08),
            units: Some(PressureUnit::parse("KPa")),
            ..SensorMeta::default()
        };
        let scale = PressureScale::from_meta(Some(&meta));
        assert_eq!(scale.unit, "kPa");
        assert!(scale.physical());
        let (label, factor) = scale.load_axis();
        assert!(label.contains("(N)"));
        assert!((factor - 5.08 * 5.08 * 1e-3).abs() < 1e-12);
        let raw = PressureScale::from_meta(None);
        assert_eq!(raw.unit, "raw counts");
        assert_eq!(raw.position_unit(), "sensels");
        assert_eq!(raw.pitches(), (1.0, 1.0));
    }
}
