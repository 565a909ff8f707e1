//! Target deflection profiles for the beam task (paper §III, Fig. 3).
//!
//! A profile maps the normalized position along the beam, t ∈ [0, 1] from the clamped-layer centre
//! to the tip-layer centre, to the normalized downward deflection of the top surface, with
//! f(0) = 0 at the clamp and f(1) = 1 at the tip.

use serde::{Deserialize, Serialize};

/// The prescribed shapes of the paper's Table III, in its order of difficulty, plus the nominal
/// homogeneous cubic as a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetProfile {
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

impl TargetProfile {
    pub const ALL: [TargetProfile; 5] = [
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_profile_runs_from_clamp_to_unit_tip() {
        for p in TargetProfile::ALL {
            assert!(p.deflection(0.0).abs() < 1e-15, "{p:?}");
            assert!((p.deflection(1.0) - 1.0).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn the_polynomial_curves_upward_in_mid_span() {
        let f = |t: f64| TargetProfile::Polynomial4.deflection(t);
        let h = 1e-3;
        let curvature = |t: f64| (f(t + h) - 2.0 * f(t) + f(t - h)) / (h * h);
        assert!(curvature(0.5) < -0.4 && curvature(0.2) > 0.0 && curvature(0.8) > 0.0);
        // ...while still deflecting downward monotonically.
        assert!((1..100).all(|i| f(i as f64 / 100.0) > f((i - 1) as f64 / 100.0)));
    }
}
