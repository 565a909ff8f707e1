//! The simulation state as flat arrays (structure of arrays): one array per voxel quantity and per
//! link quantity, allocated once when the simulation is built, never inside the step loop.

use super::error::{DynamicsError, Result};
use super::math::{Quat, Vec3};
use crate::material::{Palette, link_youngs_modulus};
use crate::voxel::VoxelGrid;

/// Per-voxel state and constants. Index `i` is the i-th filled cell in grid order.
#[derive(Clone, Debug, Default)]
pub struct Voxels {
    pub position: Vec<Vec3>,
    pub orientation: Vec<Quat>,
    pub momentum: Vec<Vec3>,
    pub angular_momentum: Vec<Vec3>,
    /// Velocity and angular velocity, kept in step with the momenta for the link damping.
    pub velocity: Vec<Vec3>,
    pub angular_velocity: Vec<Vec3>,
    /// Force and torque accumulated by the passes of the current step.
    pub force: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    pub mass: Vec<f64>,
    /// 1/m, or 0 for a fixed voxel (so a fixed voxel never moves, without a branch).
    pub inv_mass: Vec<f64>,
    /// 1/I with I = m s²/6 (a cube's inertia about any axis through its centre), or 0 if fixed.
    pub inv_inertia: Vec<f64>,
    /// Axial stiffness E·s of the voxel's own material, N/m (contact and global damping scale).
    pub stiffness: Vec<f64>,
    /// Poisson's ratio ν of the voxel's material.
    pub poisson_ratio: Vec<f64>,
    pub static_friction: Vec<f64>,
    pub kinetic_friction: Vec<f64>,
    /// Grid cell of the voxel (x, y, z), for collision adjacency and reporting.
    pub cell: Vec<[u16; 3]>,
    /// Whether the voxel's material is actuated.
    pub actuated: Vec<bool>,
}

impl Voxels {
    pub fn len(&self) -> usize {
        self.position.len()
    }
}

/// Per-link constants. A link joins voxel `a` to voxel `b`, `b` lying at +s along `axis` from `a`
/// in the rest configuration. Stiffness terms are for a square s×s section of length s:
/// A = s², I = s⁴/12, J = s⁴/6 (polar approximation).
#[derive(Clone, Debug, Default)]
pub struct Links {
    pub a: Vec<u32>,
    pub b: Vec<u32>,
    pub axis: Vec<u8>,
    /// EA/L, N/m.
    pub axial: Vec<f64>,
    /// 12EI/L³, N/m (equal to EA/L for a cube-shaped link, kept separate for clarity).
    pub shear: Vec<f64>,
    /// 6EI/L², N.
    pub coupling: Vec<f64>,
    /// EI/L, N·m (the 4EI/L and 2EI/L terms combine into ±EI/L in the mid frame, see `link`).
    pub bending: Vec<f64>,
    /// GJ/L, N·m.
    pub torsion: Vec<f64>,
    /// Stiffness-proportional damping time β = 2ζ/ω_top, s: the link's damping forces are its
    /// elastic forces evaluated on the deformation *rates* times β (see [`TOP_EIGENVALUE`]).
    pub damping_time: Vec<f64>,
    /// Fraction of the link that actuates: 0, 0.5 (one actuated end) or 1.
    pub actuated_fraction: Vec<f64>,
}

impl Links {
    pub fn len(&self) -> usize {
        self.a.len()
    }

    pub fn is_empty(&self) -> bool {
        self.a.is_empty()
    }

    /// Rest length of link `k` (m) for voxel size `voxel_size` while actuated material's linear
    /// rest-length factor is 1 + `stretch`.
    #[inline(always)]
    pub fn rest_length(&self, k: usize, voxel_size: f64, stretch: f64) -> f64 {
        (self.actuated_fraction[k] * stretch + 1.0) * voxel_size
    }
}

/// Highest eigenvalue of M⁻¹K of a dense voxel lattice in units of (EA/L)/m: the top of the
/// spectrum of the frame-link lattice with I = m s²/6 is ω_top² ≈ 13.2·EA/(L m) (power iteration
/// on a 6³ block, 13.1; a 2-voxel pair has 5, a chain 6, a sheet 11.9; see the unit test in
/// `simulation.rs`). Link damping is stiffness-proportional with β = 2ζ/ω_top, so the fastest
/// mode of the lattice gets the damping ratio ζ and a mode of frequency ω gets ζ·ω/ω_top.
/// Rounded up to 14 so that ζ never exceeds the requested ratio.
pub const TOP_EIGENVALUE: f64 = 14.0;

/// The link's stiffness-proportional damping time β = 2ζ/ω_top (s) for axial stiffness `axial`
/// (N/m), the lighter voxel's mass `m_min` (kg) and the damping ratio ζ.
pub fn link_damping_time(axial: f64, m_min: f64, zeta: f64) -> f64 {
    2.0 * zeta / (TOP_EIGENVALUE * axial / m_min).sqrt()
}

/// Builds voxels and links from a grid: voxel centres at ((x, y, z) + ½)·s, one link per pair of
/// face-adjacent filled cells. `link_damping` is the link damping ratio ζ.
pub fn build_state(
    grid: &VoxelGrid,
    palette: &Palette,
    voxel_size: f64,
    link_damping: f64,
) -> Result<(Voxels, Links)> {
    palette.validate()?;
    let dims = grid.dims();
    let count = grid.filled_count();
    if count == 0 {
        return Err(DynamicsError::Empty);
    }
    let s = voxel_size;
    let mut v = Voxels::default();
    let mut voxel_of_cell = vec![u32::MAX; dims.cell_count()];
    for (cell_index, material) in grid.cells().iter().enumerate() {
        let Some(material) = material else { continue };
        if material.index() >= palette.len() {
            return Err(DynamicsError::UnknownMaterial {
                material: material.index(),
                palette_len: palette.len(),
            });
        }
        let m = palette.get(*material);
        let [x, y, z] = dims.coords(cell_index);
        voxel_of_cell[cell_index] = v.len() as u32;
        let mass = m.density * s * s * s;
        v.position.push(Vec3::new(
            (x as f64 + 0.5) * s,
            (y as f64 + 0.5) * s,
            (z as f64 + 0.5) * s,
        ));
        v.orientation.push(Quat::IDENTITY);
        v.mass.push(mass);
        v.inv_mass.push(1.0 / mass);
        v.inv_inertia.push(6.0 / (mass * s * s));
        v.stiffness.push(m.youngs_modulus * s);
        v.poisson_ratio.push(m.poisson_ratio);
        v.static_friction.push(m.static_friction);
        v.kinetic_friction.push(m.kinetic_friction);
        v.cell.push([x as u16, y as u16, z as u16]);
        v.actuated.push(m.actuated);
    }
    let n = v.len();
    for field in [
        &mut v.momentum,
        &mut v.angular_momentum,
        &mut v.velocity,
        &mut v.angular_velocity,
        &mut v.force,
        &mut v.torque,
    ] {
        *field = vec![Vec3::ZERO; n];
    }

    // Links by axis, each axis in grid order: along the body's solid runs four consecutive links
    // join four consecutive voxels to four consecutive voxels, which the link pass reads and
    // writes as blocks (see `link::link_pass`).
    let mut l = Links::default();
    for axis in 0..3u8 {
        for (cell_index, material) in grid.cells().iter().enumerate() {
            let Some(ma) = material else { continue };
            let [x, y, z] = dims.coords(cell_index);
            let (nx, ny, nz) = match axis {
                0 => (x + 1, y, z),
                1 => (x, y + 1, z),
                _ => (x, y, z + 1),
            };
            if nx >= dims.nx || ny >= dims.ny || nz >= dims.nz {
                continue;
            }
            let Some(mb) = grid.get(nx, ny, nz) else {
                continue;
            };
            let (a, b) = (
                voxel_of_cell[cell_index],
                voxel_of_cell[dims.index(nx, ny, nz)],
            );
            let (pa, pb) = (palette.get(*ma), palette.get(mb));
            let e = link_youngs_modulus(pa.youngs_modulus, pb.youngs_modulus);
            let g = link_youngs_modulus(pa.shear_modulus(), pb.shear_modulus());
            let (area, inertia, polar) = (s * s, s.powi(4) / 12.0, s.powi(4) / 6.0);
            let axial = e * area / s;
            let bending = e * inertia / s;
            l.a.push(a);
            l.b.push(b);
            l.axis.push(axis);
            l.axial.push(axial);
            l.shear.push(12.0 * e * inertia / (s * s * s));
            l.coupling.push(6.0 * e * inertia / (s * s));
            l.bending.push(bending);
            l.torsion.push(g * polar / s);
            let m_min = v.mass[a as usize].min(v.mass[b as usize]);
            l.damping_time
                .push(link_damping_time(axial, m_min, link_damping));
            l.actuated_fraction
                .push(0.5 * (f64::from(u8::from(pa.actuated)) + f64::from(u8::from(pb.actuated))));
        }
    }
    Ok((v, l))
}
