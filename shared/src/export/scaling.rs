//! Physical scaling of an evolved robot (paper §IV-C, Table IV): a robot evolved at one voxel size
//! and material is built at another, and its actuation period is chosen so that the effective
//! dynamic actuation force F_d = m d f² is unchanged (m the mass, d the actuation displacement,
//! f the actuation frequency).
//!
//! With every length scaled by k = s'/s, the mass scales by (ρ'/ρ) k³ and the displacement (the
//! same relative expansion) by k, so f'² = f² m d / (m' d') = f² / ((ρ'/ρ) k⁴), i.e.
//! T' = T k² √(ρ'/ρ).

/// A robot's physical size and material, as far as the actuation force is concerned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicalBuild {
    /// Voxel edge length, m.
    pub voxel_size: f64,
    /// Material density, kg/m³.
    pub density: f64,
}

/// The actuation period at `to` that gives the same F_d = m d f² as `period` at `from`, for
/// the same design (same voxels, same relative actuation amplitude).
pub fn equivalent_actuation_period(period: f64, from: PhysicalBuild, to: PhysicalBuild) -> f64 {
    let k = to.voxel_size / from.voxel_size;
    period * k * k * (to.density / from.density).sqrt()
}

/// F_d = m d f² for a body of `voxels` voxels whose actuated length changes by the fraction
/// `linear_amplitude`, at actuation period `period`.
pub fn dynamic_actuation_force(
    build: PhysicalBuild,
    voxels: usize,
    linear_amplitude: f64,
    period: f64,
) -> f64 {
    let mass = build.density * build.voxel_size.powi(3) * voxels as f64;
    let displacement = linear_amplitude * build.voxel_size;
    mass * displacement / (period * period)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scaled_period_keeps_the_dynamic_actuation_force() {
        let evolved = PhysicalBuild {
            voxel_size: 1e-3,
            density: 500.0,
        };
        for to in [
            PhysicalBuild {
                voxel_size: 1e-3,
                density: 500.0,
            },
            PhysicalBuild {
                voxel_size: 6.35e-3,
                density: 90.0,
            },
            PhysicalBuild {
                voxel_size: 0.05,
                density: 1200.0,
            },
        ] {
            let period = equivalent_actuation_period(0.07, evolved, to);
            let before = dynamic_actuation_force(evolved, 3544, 0.0627, 0.07);
            let after = dynamic_actuation_force(to, 3544, 0.0627, period);
            assert!(
                (after - before).abs() <= 1e-12 * before,
                "{before} vs {after}"
            );
        }
        // Twice the size in the same material: four times the period.
        let twice = PhysicalBuild {
            voxel_size: 2e-3,
            density: 500.0,
        };
        assert!((equivalent_actuation_period(0.07, evolved, twice) - 0.28).abs() < 1e-15);
    }
}
