//! The 3-D Euler–Bernoulli frame element of one link, in the solver's scaled unknowns.
//!
//! A link joins two face-adjacent voxels of size s: length L = s, square section s×s, so
//! A = s², I = s⁴/12 and J ≈ s⁴/6. The solver works with the rotations scaled by s
//! (θ̃ = s·θ, moments M̃ = M/s), which makes every entry of the element matrix a multiple of s:
//!
//! | entry | SI value | scaled |
//! |---|---|---|
//! | axial EA/L, transverse 12EI/L³ | E s | E s |
//! | translation–rotation 6EI/L² | E s²/2 | E s/2 |
//! | rotation 4EI/L, 2EI/L | E s³/3, E s³/6 | E s/3, E s/6 |
//! | torsion GJ/L | G s³/6 | G s/6 |
//!
//! so translations and rotations are equally weighted for the preconditioner and for the
//! rigid-body modes of the multigrid. Every link is axis-aligned: its local frame (axial,
//! transverse 1, transverse 2) is the cyclic permutation (a, a+1, a+2) of the global axes, a
//! right-handed frame, so the global matrix is the local one with permuted indices and no
//! rotation matrix.

/// A 6×6 block, row-major.
pub(crate) type Block = [f64; 36];

/// The three distinct 6×6 blocks of a link from node i (lower) to node j (upper along the axis):
/// `K_ii`, `K_ij` (`K_ji` is its transpose) and `K_jj`, each split into the part proportional to
/// the axial/bending stiffness a = E s and the part proportional to the torsion stiffness
/// g = G s / 6, so a link's blocks are `a * unit_a + g * unit_g`.
#[derive(Clone, Debug)]
pub(crate) struct LinkBlocks {
    /// `[ii, ij, jj]` per unit a, per axis.
    pub bend: [[Block; 3]; 3],
    /// `[ii, ij, jj]` per unit g, per axis.
    pub twist: [[Block; 3]; 3],
}

/// Local entries of the element in scaled unknowns per unit a: `(block, row, col, value)` with
/// block 0 = ii, 1 = ij, 2 = jj and local DOF order (u, v, w, θx, θy, θz), x axial.
const BEND_LOCAL: [(usize, usize, usize, f64); 27] = [
    // axial
    (0, 0, 0, 1.0),
    (1, 0, 0, -1.0),
    (2, 0, 0, 1.0),
    // bending in the x–y plane (v, θz)
    (0, 1, 1, 1.0),
    (0, 1, 5, 0.5),
    (0, 5, 1, 0.5),
    (0, 5, 5, 1.0 / 3.0),
    (1, 1, 1, -1.0),
    (1, 1, 5, 0.5),
    (1, 5, 1, -0.5),
    (1, 5, 5, 1.0 / 6.0),
    (2, 1, 1, 1.0),
    (2, 1, 5, -0.5),
    (2, 5, 1, -0.5),
    (2, 5, 5, 1.0 / 3.0),
    // bending in the x–z plane (w, θy): the coupling changes sign
    (0, 2, 2, 1.0),
    (0, 2, 4, -0.5),
    (0, 4, 2, -0.5),
    (0, 4, 4, 1.0 / 3.0),
    (1, 2, 2, -1.0),
    (1, 2, 4, -0.5),
    (1, 4, 2, 0.5),
    (1, 4, 4, 1.0 / 6.0),
    (2, 2, 2, 1.0),
    (2, 2, 4, 0.5),
    (2, 4, 2, 0.5),
    (2, 4, 4, 1.0 / 3.0),
];

/// Local torsion entries per unit g.
const TWIST_LOCAL: [(usize, usize, usize, f64); 3] =
    [(0, 3, 3, 1.0), (1, 3, 3, -1.0), (2, 3, 3, 1.0)];

/// Global DOF of local DOF `k` for a link along `axis`.
fn global_dof(axis: usize, k: usize) -> usize {
    let base = if k < 3 { 0 } else { 3 };
    base + (axis + k % 3) % 3
}

fn scatter(entries: &[(usize, usize, usize, f64)], axis: usize) -> [Block; 3] {
    let mut blocks = [[0.0; 36]; 3];
    for &(b, r, c, v) in entries {
        blocks[b][6 * global_dof(axis, r) + global_dof(axis, c)] += v;
    }
    blocks
}

impl LinkBlocks {
    pub fn new() -> Self {
        Self {
            bend: [0, 1, 2].map(|axis| scatter(&BEND_LOCAL, axis)),
            twist: [0, 1, 2].map(|axis| scatter(&TWIST_LOCAL, axis)),
        }
    }

    /// Block `which` (0 = ii, 1 = ij, 2 = jj) of a link along `axis` with stiffnesses a, g.
    #[inline]
    pub fn block(&self, axis: usize, which: usize, a: f64, g: f64) -> Block {
        let bend = &self.bend[axis][which];
        let twist = &self.twist[axis][which];
        std::array::from_fn(|k| a * bend[k] + g * twist[k])
    }
}

/// The transpose of a block.
#[inline]
pub(crate) fn transpose(b: &Block) -> Block {
    std::array::from_fn(|k| b[6 * (k % 6) + k / 6])
}

#[cfg(test)]
mod tests;
