//! Typed errors of the navigation layer, each carrying the offending values.

/// A broadcast field outside its interface document's range.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NavError {
    /// `field` = `value` is outside [`min`, `max`].
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
}

impl core::fmt::Display for NavError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            NavError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(f, "{field} = {value} is out of range [{min}, {max}]"),
        }
    }
}

impl core::error::Error for NavError {}

#[cfg(test)]
mod tests {
    use super::NavError;

    /// A broadcast field refused by its ICD range names the field, the
    /// value and the range (a GLONASS 1020 outside the ICD is counted
    /// `glonass_bad` with this error).
    ///
    /// Verifies: WIRE-TEXT
    #[test]
    fn the_text_names_the_field_value_and_range() {
        let e = NavError::OutOfRange {
            field: "x_m",
            value: 3.0e8,
            min: -2.7e7,
            max: 2.7e7,
        };
        assert_eq!(
            std::format!("{e}"),
            "x_m = 300000000 is out of range [-27000000, 27000000]"
        );
    }
}
