//! Target deflection profiles for the beam task (paper §III, Fig. 3).
//!
//! A profile maps the normalized position along the beam, t ∈ [0, 1] from the clamped-layer centre
//! to the tip-layer centre, to the normalized downward deflection of the top surface, with
//! f(0) = 0 at the clamp and f(1) = 1 at the tip.

use serde::{Deserialize, Serialize};

use super::custom::CustomProfile;

/// The prescribed shapes of the paper's Table III, in its order of difficulty, plus the nominal
/// homogeneous cubic as a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NamedProfile {
    /// A straight line from clamp to tip: f = t (the beam must hinge at the root).
    Straight,
    /// A circular arc tangent to the clamp: f = t², the small-deflection arc of constant curvature.
    CircularArc,
    /// Two straight pieces with a slope jump at mid-span: slope 1/2 then 3/2.
    DiscontinuousSlope,
    /// f = 3.5t² − 5t³ + 2.5t⁴: monotone, but curving upward (f'' < 0) for t in (0.37, 0.63).
    Polynomial4,
    /// The homogeneous Euler–Bernoulli cantilever under a tip load: f = (3t² − t³)/2.
    NominalCubic,
}

impl NamedProfile {
    pub const ALL: [NamedProfile; 5] = [
        Self::Straight,
        Self::CircularArc,
        Self::DiscontinuousSlope,
        Self::Polynomial4,
        Self::NominalCubic,
    ];

    /// Normalized deflection at normalized position `t`.
    pub fn deflection(self, t: f64) -> f64 {
        match self {
            Self::Straight => t,
            Self::CircularArc => t * t,
            Self::DiscontinuousSlope => {
                if t <= 0.5 {
                    0.5 * t
                } else {
                    0.25 + 1.5 * (t - 0.5)
                }
            }
            Self::Polynomial4 => t * t * (3.5 - 5.0 * t + 2.5 * t * t),
            Self::NominalCubic => 0.5 * t * t * (3.0 - t),
        }
    }

    /// The simulated RMS error the paper reached for this shape (Table III), in percent of the tip
    /// deflection; `None` for the nominal check, which the paper did not evolve.
    pub fn paper_rms_percent(self) -> Option<f64> {
        match self {
            Self::Straight => Some(0.10),
            Self::CircularArc => Some(0.10),
            Self::DiscontinuousSlope => Some(0.86),
            Self::Polynomial4 => Some(0.90),
            Self::NominalCubic => None,
        }
    }

    /// The profile called `name` in a config.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Straight => "straight",
            Self::CircularArc => "circular_arc",
            Self::DiscontinuousSlope => "discontinuous_slope",
            Self::Polynomial4 => "polynomial4",
            Self::NominalCubic => "nominal_cubic",
        }
    }
}

/// A beam's target: one of the named profiles, or one the designer writes.
#[derive(Clone, Debug, PartialEq)]
pub enum TargetProfile {
    Named(NamedProfile),
    Custom(CustomProfile),
}

impl TargetProfile {
    /// Normalized deflection at normalized position `t` ∈ [0, 1].
    pub fn deflection(&self, t: f64) -> f64 {
        match self {
            Self::Named(p) => p.deflection(t),
            Self::Custom(p) => p.deflection(t),
        }
    }

    /// The paper's simulated RMS error for this shape (Table III); none for a custom profile.
    pub fn paper_rms_percent(&self) -> Option<f64> {
        match self {
            Self::Named(p) => p.paper_rms_percent(),
            Self::Custom(_) => None,
        }
    }

    /// How summaries, reports and plots name the target: its name, its CSV file, or
    /// "custom (N points)".
    pub fn label(&self) -> String {
        match self {
            Self::Named(p) => p.name().to_string(),
            Self::Custom(p) => p.label(),
        }
    }

    pub fn validate(&self) -> Result<(), crate::task::SceneError> {
        match self {
            Self::Named(_) => Ok(()),
            Self::Custom(p) => p.validate(),
        }
    }
}

impl From<NamedProfile> for TargetProfile {
    fn from(p: NamedProfile) -> Self {
        Self::Named(p)
    }
}

// A named profile is written as its name, exactly as before custom profiles existed, so stored
// configs and scene hashes of named targets are unchanged; a custom one as its table.
impl Serialize for TargetProfile {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Named(p) => p.serialize(s),
            Self::Custom(p) => p.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for TargetProfile {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = TargetProfile;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a profile name or a table with `points` or `csv`")
            }

            fn visit_str<E: serde::de::Error>(self, name: &str) -> Result<TargetProfile, E> {
                NamedProfile::from_name(name)
                    .map(TargetProfile::Named)
                    .ok_or_else(|| {
                        let names: Vec<&str> = NamedProfile::ALL.iter().map(|p| p.name()).collect();
                        E::custom(format!(
                            "unknown target profile '{name}', expected one of {} or a table with `points` or `csv`",
                            names.join(", ")
                        ))
                    })
            }

            // Deserialising the table through the map keeps the custom profile's own error
            // (an unknown key, a malformed point) instead of an untagged enum's generic one.
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<TargetProfile, A::Error> {
                CustomProfile::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(TargetProfile::Custom)
            }
        }
        d.deserialize_any(Visitor)
    }
}

#[cfg(test)]
mod tests;
