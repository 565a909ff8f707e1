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
mod tests;
