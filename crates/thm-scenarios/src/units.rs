//! Physical quantities in scenario files: a number in SI units, or a string `"value unit"`.
//!
//! `radius = 5e-4` and `radius = "0.5 mm"` mean the same. A unit of the wrong dimension is an
//! error naming the allowed units. The resolved scenario keeps the value as it was written.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::ConfigError;

/// A physical dimension: its name and the units accepted for it.
pub trait Dimension {
    /// What the dimension is, e.g. `a pressure`.
    const WHAT: &'static str;
    /// Accepted units: `(symbol, scale, offset)` with `si = value · scale + offset`. The
    /// first is the SI unit that a bare number is taken in.
    const UNITS: &'static [(&'static str, f64, f64)];
}

macro_rules! dimension {
    ($(#[$m:meta])* $name:ident, $what:literal, [$(($sym:literal, $scale:expr, $off:expr)),+ $(,)?]) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $name;
        impl Dimension for $name {
            const WHAT: &'static str = $what;
            const UNITS: &'static [(&'static str, f64, f64)] = &[$(($sym, $scale, $off)),+];
        }
    };
}

dimension!(/// Time.
    Time, "a time", [("s", 1.0, 0.0), ("ms", 1e-3, 0.0), ("us", 1e-6, 0.0), ("min", 60.0, 0.0), ("h", 3600.0, 0.0)]);
dimension!(/// Length.
    Length, "a length", [("m", 1.0, 0.0), ("cm", 1e-2, 0.0), ("mm", 1e-3, 0.0), ("um", 1e-6, 0.0)]);
dimension!(/// Thermodynamic temperature.
    Temperature, "a temperature", [("K", 1.0, 0.0), ("degC", 1.0, 273.15)]);
dimension!(/// Pressure or stress (for the mechanical scenario kinds).
    Pressure, "a pressure", [("Pa", 1.0, 0.0), ("kPa", 1e3, 0.0), ("MPa", 1e6, 0.0), ("GPa", 1e9, 0.0)]);
dimension!(/// Velocity.
    Velocity, "a velocity", [("m/s", 1.0, 0.0), ("mm/s", 1e-3, 0.0), ("um/s", 1e-6, 0.0)]);
dimension!(/// Mass density.
    Density, "a density", [("kg/m^3", 1.0, 0.0), ("g/cm^3", 1e3, 0.0)]);
dimension!(/// Specific heat capacity.
    SpecificHeat, "a specific heat", [("J/(kg K)", 1.0, 0.0), ("kJ/(kg K)", 1e3, 0.0)]);
dimension!(/// Heat-transfer coefficient.
    HeatTransferCoefficient, "a heat-transfer coefficient", [("W/(m^2 K)", 1.0, 0.0)]);

/// A value of dimension `D`, held in SI, remembering how it was written.
#[derive(Debug, Clone, PartialEq)]
pub struct Quantity<D> {
    si: f64,
    /// The value in the unit it was written in, and that unit's index in `D::UNITS`.
    given: f64,
    unit: usize,
    /// Whether it was written as a string with a unit (else a bare SI number).
    with_unit: bool,
    _d: PhantomData<D>,
}

impl<D: Dimension> Quantity<D> {
    /// A value in the given unit (must be one of `D::UNITS`; falls back to SI otherwise).
    pub fn new(value: f64, unit: &str) -> Self {
        let k = D::UNITS.iter().position(|u| u.0 == unit).unwrap_or(0);
        let (_, scale, offset) = D::UNITS[k];
        Self {
            si: value * scale + offset,
            given: value,
            unit: k,
            with_unit: true,
            _d: PhantomData,
        }
    }

    /// The value in SI units.
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn si(&self) -> f64 {
        self.si
    }

    /// The unit it was written in.
    pub fn unit(&self) -> &'static str {
        D::UNITS[self.unit].0
    }

    /// An SI value expressed in the unit this quantity was written in.
    fn in_given_unit(&self, si: f64) -> f64 {
        let (_, scale, offset) = D::UNITS[self.unit];
        (si - offset) / scale
    }

    fn fail(&self, path: &str, requirement: String) -> ConfigError {
        ConfigError::new(
            path,
            format!("must be {requirement}, got {} {}", self.given, self.unit()),
        )
    }

    /// The SI value if it is finite and `> lower` (SI).
    pub fn above(&self, path: &str, lower: f64) -> Result<f64, ConfigError> {
        if self.si.is_finite() && self.si > lower {
            Ok(self.si)
        } else {
            Err(self.fail(
                path,
                format!("> {} {}", self.in_given_unit(lower), self.unit()),
            ))
        }
    }

    /// The SI value if it is finite and `> 0`.
    pub fn positive(&self, path: &str) -> Result<f64, ConfigError> {
        self.above(path, 0.0)
    }

    /// The SI value if it lies in `[lo, hi]` (SI).
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn within(&self, path: &str, lo: f64, hi: f64) -> Result<f64, ConfigError> {
        if self.si.is_finite() && self.si >= lo && self.si <= hi {
            Ok(self.si)
        } else {
            let u = self.unit();
            Err(self.fail(
                path,
                format!(
                    "in [{} {u}, {} {u}]",
                    self.in_given_unit(lo),
                    self.in_given_unit(hi)
                ),
            ))
        }
    }
}

fn units_list<D: Dimension>() -> String {
    D::UNITS
        .iter()
        .map(|u| format!("`{}`", u.0))
        .collect::<Vec<_>>()
        .join(", ")
}

impl<D: Dimension> Serialize for Quantity<D> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.with_unit {
            s.serialize_str(&format!("{} {}", self.given, self.unit()))
        } else {
            s.serialize_f64(self.si)
        }
    }
}

struct QuantityVisitor<D>(PhantomData<D>);

impl<D: Dimension> Visitor<'_> for QuantityVisitor<D> {
    type Value = Quantity<D>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: a number in {} or a string \"value unit\" with unit one of {}",
            D::WHAT,
            D::UNITS[0].0,
            units_list::<D>()
        )
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
        Ok(Quantity {
            si: v,
            given: v,
            unit: 0,
            with_unit: false,
            _d: PhantomData,
        })
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
        self.visit_f64(v as f64)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
        self.visit_f64(v as f64)
    }

    fn visit_str<E: de::Error>(self, text: &str) -> Result<Self::Value, E> {
        let text = text.trim();
        let split = text.find(char::is_whitespace).unwrap_or(text.len());
        let (number, unit) = (text[..split].trim(), text[split..].trim());
        let value: f64 = number.parse().map_err(|_| {
            E::custom(format!(
                "`{text}` is not \"value unit\" (expected {}, e.g. \"1.5 {}\")",
                D::WHAT,
                D::UNITS[0].0
            ))
        })?;
        let unit = if unit.is_empty() { D::UNITS[0].0 } else { unit };
        if !D::UNITS.iter().any(|u| u.0 == unit) {
            return Err(E::custom(format!(
                "unit `{unit}` is not {}; use one of {}",
                D::WHAT,
                units_list::<D>()
            )));
        }
        Ok(Quantity::new(value, unit))
    }
}

impl<'de, D: Dimension> Deserialize<'de> for Quantity<D> {
    fn deserialize<De: Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        d.deserialize_any(QuantityVisitor(PhantomData))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize, Serialize)]
    struct Probe {
        p: Quantity<Pressure>,
        t: Quantity<Temperature>,
    }

    #[test]
    fn units_convert_to_si_and_serialize_as_written() {
        let p: Probe = toml::from_str("p = \"3 MPa\"\nt = \"20 degC\"").unwrap();
        assert_eq!(p.p.si(), 3e6);
        assert_eq!(p.t.si(), 293.15);
        let bare: Probe = toml::from_str("p = 5\nt = 300.5").unwrap();
        assert_eq!((bare.p.si(), bare.t.si()), (5.0, 300.5));
        let back = toml::to_string(&p).unwrap();
        assert!(
            back.contains("p = \"3 MPa\"") && back.contains("t = \"20 degC\""),
            "{back}"
        );
    }

    #[test]
    fn wrong_unit_names_the_allowed_units_and_range_errors_use_the_given_unit() {
        let e = toml::from_str::<Probe>("p = \"3 m\"\nt = 1")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("unit `m` is not a pressure") && e.contains("`MPa`"),
            "{e}"
        );
        let p: Probe = toml::from_str("p = \"-3 MPa\"\nt = \"-300 degC\"").unwrap();
        let e = p.p.positive("solid.contact.tensile_strength").unwrap_err();
        assert_eq!(
            e.to_string(),
            "solid.contact.tensile_strength: must be > 0 MPa, got -3 MPa"
        );
        let e = p.t.positive("fluid.temperature").unwrap_err().to_string();
        assert!(e.contains("must be > -273.15 degC, got -300 degC"), "{e}");
        let nan: Probe = toml::from_str("p = nan\nt = 1").unwrap();
        assert!(nan.p.within("p", 0.0, 1.0).is_err());
    }
}
