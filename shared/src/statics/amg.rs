//! Smoothed-aggregation algebraic multigrid, used as the preconditioner of CG.
//!
//! Aggregates are the 2×2×2 blocks of the voxel grid (geometric aggregation, recursively on the
//! coarse grids). The tentative prolongator maps each aggregate's six rigid-body modes
//! (translations and infinitesimal rotations, orthonormalised per aggregate) to one coarse node
//! with six unknowns; Jacobi smoothing `P = (I − ω D⁻¹A) P_tent` lowers the energy of the coarse
//! basis; coarse operators are Galerkin products `Pᵀ A P`. The V-cycle does forward block
//! Gauss–Seidel before the coarse correction and backward after, which makes it a symmetric
//! positive definite preconditioner, and solves the coarsest level with a sparse Cholesky. The
//! hierarchy is built in double precision; the V-cycle runs on single-precision copies of its
//! matrices and vectors (`single.rs`: it is memory-bound, and a preconditioner need not be exact).

use super::bsr::{BlockMatrix, DistinctBlocks, RowByRow, block_gemm_add};
use super::direct::DirectFactor;
use super::element::Block;
use super::error::Result;
use super::params::MultigridParams;
use super::pcg::{Precondition, inverse_diagonal_blocks};
use super::single::{Block32, BlockMatrix32, block32, block32_mul_add};
use super::spgemm::galerkin_product;
use super::wide::with_wide_vectors;

/// One level of the V-cycle, in single precision.
#[derive(Debug)]
struct Level {
    a: BlockMatrix32,
    inverse_diagonal: DistinctBlocks<Block32>,
    /// Prolongator to the next level (fine rows × coarse columns) and its transpose.
    p: BlockMatrix32,
    r: BlockMatrix32,
    /// Scratch: right-hand side, solution and residual of this level.
    b: Vec<f32>,
    x: Vec<f32>,
    res: Vec<f32>,
}

/// The multigrid hierarchy and its V-cycle.
#[derive(Debug)]
pub(crate) struct Multigrid {
    levels: Vec<Level>,
    coarse_factor: DirectFactor,
    /// The coarsest level's right-hand side and solution, in double for the factor, and in
    /// single for the level above.
    coarse_b: Vec<f64>,
    coarse_x: Vec<f32>,
}

/// Rigid-body modes of a node at grid position `x` in scaled unknowns (u, s θ) divided by s:
/// column m < 3 translates along m, column 3 + w rotates about axis w through the origin.
fn rigid_modes(x: [f64; 3]) -> Block {
    let mut b = [0.0; 36];
    for k in 0..3 {
        b[6 * k + k] = 1.0;
        b[6 * (3 + k) + 3 + k] = 1.0;
    }
    // u = e_w × x
    b[6 + 3] = -x[2];
    b[2 * 6 + 3] = x[1];
    b[3 + 1] = x[2];
    b[2 * 6 + 4] = -x[0];
    b[5] = -x[1];
    b[6 + 5] = x[0];
    b
}

/// The aggregates of one level: aggregate of each node, coarse coordinates.
fn aggregate(coords: &[[u32; 3]]) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut extent = [0usize; 3];
    for c in coords {
        for (e, &ck) in extent.iter_mut().zip(c) {
            *e = (*e).max(ck as usize / 2 + 1);
        }
    }
    let mut id_of_key = vec![u32::MAX; extent[0] * extent[1] * extent[2]];
    let mut aggregate_of = Vec::with_capacity(coords.len());
    let mut coarse_coords = Vec::new();
    for c in coords {
        let key = [c[0] / 2, c[1] / 2, c[2] / 2];
        let flat = key[0] as usize + extent[0] * (key[1] as usize + extent[1] * key[2] as usize);
        if id_of_key[flat] == u32::MAX {
            id_of_key[flat] = coarse_coords.len() as u32;
            coarse_coords.push(key);
        }
        aggregate_of.push(id_of_key[flat]);
    }
    (aggregate_of, coarse_coords)
}

/// Orthonormalises the near-null-space blocks of each aggregate (modified Gram–Schmidt, twice
/// for stability): returns Q's block per node and R per aggregate, B_agg = Q R.
fn orthonormalise(
    modes: &[Block],
    aggregate_of: &[u32],
    aggregates: usize,
) -> (Vec<Block>, Vec<Block>) {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); aggregates];
    for (node, &a) in aggregate_of.iter().enumerate() {
        members[a as usize].push(node);
    }
    let mut q = modes.to_vec();
    let mut r_blocks = vec![[0.0; 36]; aggregates];
    for (a, nodes) in members.iter().enumerate() {
        let r = &mut r_blocks[a];
        for j in 0..6 {
            for _pass in 0..2 {
                for k in 0..j {
                    let mut dot = 0.0;
                    for &n in nodes {
                        for row in 0..6 {
                            dot += q[n][6 * row + k] * q[n][6 * row + j];
                        }
                    }
                    r[6 * k + j] += dot;
                    for &n in nodes {
                        for row in 0..6 {
                            q[n][6 * row + j] -= dot * q[n][6 * row + k];
                        }
                    }
                }
            }
            let norm = nodes
                .iter()
                .map(|&n| (0..6).map(|row| q[n][6 * row + j].powi(2)).sum::<f64>())
                .sum::<f64>()
                .sqrt();
            r[6 * j + j] = norm;
            for &n in nodes {
                for row in 0..6 {
                    q[n][6 * row + j] /= norm;
                }
            }
        }
    }
    (q, r_blocks)
}

/// λ_max(D⁻¹A) by power iteration from a fixed start vector (deterministic), on the single-
/// precision copies: the prolongator smoothing needs it to ~10 %, and it is memory-bound.
fn spectral_radius(
    a: &BlockMatrix32,
    inverse_diagonal: &DistinctBlocks<Block32>,
    iterations: usize,
) -> f64 {
    let n = 6 * a.n;
    let mut v: Vec<f32> = (0..n).map(|i| 1.0 + (i % 7) as f32 / 7.0).collect();
    let mut w = vec![0.0; n];
    let mut lambda = 1.0;
    for _ in 0..iterations {
        let norm = v
            .iter()
            .map(|&x| f64::from(x) * f64::from(x))
            .sum::<f64>()
            .sqrt();
        v.iter_mut()
            .for_each(|x| *x = (f64::from(*x) / norm) as f32);
        a.mul_vec(&v, &mut w);
        for (row, wr) in w.chunks_exact_mut(6).enumerate() {
            let mut acc = [0.0; 6];
            block32_mul_add(inverse_diagonal.get(row), wr, &mut acc);
            wr.copy_from_slice(&acc);
        }
        lambda = w
            .iter()
            .map(|&x| f64::from(x) * f64::from(x))
            .sum::<f64>()
            .sqrt();
        std::mem::swap(&mut v, &mut w);
    }
    lambda
}

/// The smoothed prolongator P = (I − ω D⁻¹ A) P_tent, with P_tent = one block Q_i per row at the
/// node's aggregate.
fn smoothed_prolongator(
    a: &BlockMatrix,
    inverse_diagonal: &DistinctBlocks,
    q: &[Block],
    aggregate_of: &[u32],
    omega: f64,
) -> BlockMatrix {
    with_wide_vectors(
        #[inline(always)]
        || smoothed_rows(a, inverse_diagonal, q, aggregate_of, omega),
    )
}

#[inline(always)]
fn smoothed_rows(
    a: &BlockMatrix,
    inverse_diagonal: &DistinctBlocks,
    q: &[Block],
    aggregate_of: &[u32],
    omega: f64,
) -> BlockMatrix {
    let mut p_rows = RowByRow::with_capacity(a.n, 4 * a.n);
    let mut row: Vec<(u32, Block)> = Vec::with_capacity(8);
    for i in 0..a.n {
        row.clear();
        let (a_cols, a_blocks) = a.row(i);
        for (&j, a_block) in a_cols.iter().zip(a_blocks) {
            let agg = aggregate_of[j as usize];
            let slot = match row.iter().position(|&(c, _)| c == agg) {
                Some(k) => k,
                None => {
                    row.push((agg, [0.0; 36]));
                    row.len() - 1
                }
            };
            block_gemm_add(a_block, &q[j as usize], &mut row[slot].1);
        }
        let own = aggregate_of[i];
        for (c, ap) in row.iter_mut() {
            let mut smoothed = [0.0; 36];
            block_gemm_add(inverse_diagonal.get(i), ap, &mut smoothed);
            for (o, s) in ap.iter_mut().zip(smoothed) {
                *o = -omega * s;
            }
            if *c == own {
                for (o, t) in ap.iter_mut().zip(&q[i]) {
                    *o += t;
                }
            }
        }
        row.sort_unstable_by_key(|&(c, _)| c);
        p_rows.push_row(row.iter().map(|(c, b)| (*c, b)));
    }
    p_rows.finish()
}

impl Multigrid {
    /// Builds the hierarchy for `a`, whose block rows sit at grid `coords`.
    pub fn new(fine: &BlockMatrix, coords: &[[u32; 3]], params: &MultigridParams) -> Result<Self> {
        let mut levels = Vec::new();
        // The fine matrix is borrowed (CG keeps it); each coarse one is owned by this loop.
        let mut coarser: Option<BlockMatrix> = None;
        let mut coords = coords.to_vec();
        let mut modes: Vec<Block> = coords
            .iter()
            .map(|c| rigid_modes([f64::from(c[0]), f64::from(c[1]), f64::from(c[2])]))
            .collect();
        loop {
            let a = coarser.as_ref().unwrap_or(fine);
            if a.n <= params.coarse_max_nodes || levels.len() + 1 >= params.max_levels {
                break;
            }
            let (aggregate_of, coarse_coords) = aggregate(&coords);
            let nc = coarse_coords.len();
            if 2 * nc > a.n {
                break; // aggregation no longer coarsens (a thin sliver): solve directly here
            }
            let inverse_diagonal = inverse_diagonal_blocks(a)?;
            let a32 = BlockMatrix32::from_f64(a);
            let inverse_diagonal32 = inverse_diagonal.map(block32);
            let lambda = spectral_radius(&a32, &inverse_diagonal32, params.power_iterations);
            let omega = params.prolongator_damping / lambda;
            let (q, coarse_modes) = orthonormalise(&modes, &aggregate_of, nc);
            let p = smoothed_prolongator(a, &inverse_diagonal, &q, &aggregate_of, omega);
            let coarse = galerkin_product(a, &p, nc);
            let dof = a.dof();
            levels.push(Level {
                a: a32,
                inverse_diagonal: inverse_diagonal32,
                p: BlockMatrix32::from_f64(&p),
                r: BlockMatrix32::transpose_from_f64(&p, nc),
                b: vec![0.0; dof],
                x: vec![0.0; dof],
                res: vec![0.0; dof],
            });
            coarser = Some(coarse);
            coords = coarse_coords;
            modes = coarse_modes;
        }
        let a = coarser.as_ref().unwrap_or(fine);
        let coarse_factor = DirectFactor::new(a)?;
        Ok(Self {
            levels,
            coarse_factor,
            coarse_b: vec![0.0; a.dof()],
            coarse_x: vec![0.0; a.dof()],
        })
    }

    /// Number of levels, the directly solved coarsest included.
    pub fn level_count(&self) -> usize {
        self.levels.len() + 1
    }

    /// x = V-cycle(b) on level `l`, reading `levels[l].b` and writing `levels[l].x`.
    fn v_cycle(&mut self, l: usize, sweeps: usize) {
        if l == self.levels.len() {
            self.coarse_factor.solve_in_place(&mut self.coarse_b);
            for (x, b) in self.coarse_x.iter_mut().zip(&self.coarse_b) {
                *x = *b as f32;
            }
            return;
        }
        let (head, tail) = self.levels.split_at_mut(l + 1);
        let level = &mut head[l];
        level.x.fill(0.0);
        for _ in 0..sweeps {
            let (a, d) = (&level.a, &level.inverse_diagonal);
            a.gauss_seidel(d, &level.b, &mut level.x, false);
        }
        level.a.residual(&level.b, &level.x, &mut level.res);
        match tail.first_mut() {
            Some(next) => level.r.mul_vec(&level.res, &mut next.b),
            None => {
                // The coarsest right-hand side, through `coarse_x`, in double for the factor.
                level.r.mul_vec(&level.res, &mut self.coarse_x);
                for (b, c) in self.coarse_b.iter_mut().zip(&self.coarse_x) {
                    *b = f64::from(*c);
                }
            }
        }
        self.v_cycle(l + 1, sweeps);
        let (head, tail) = self.levels.split_at_mut(l + 1);
        let level = &mut head[l];
        let coarse_x = match tail.first() {
            Some(next) => &next.x,
            None => &self.coarse_x,
        };
        level.p.mul_vec_add(coarse_x, &mut level.x);
        for _ in 0..sweeps {
            let (a, d) = (&level.a, &level.inverse_diagonal);
            a.gauss_seidel(d, &level.b, &mut level.x, true);
        }
    }
}

/// The V-cycle as a CG preconditioner, with its sweep count.
#[derive(Debug)]
pub(crate) struct MultigridPreconditioner {
    pub multigrid: Multigrid,
    pub sweeps: usize,
}

impl Precondition for MultigridPreconditioner {
    fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        let mg = &mut self.multigrid;
        if mg.levels.is_empty() {
            mg.coarse_b.copy_from_slice(r);
            mg.coarse_factor.solve_in_place(&mut mg.coarse_b);
            z.copy_from_slice(&mg.coarse_b);
            return;
        }
        for (b, r) in mg.levels[0].b.iter_mut().zip(r) {
            *b = *r as f32;
        }
        mg.v_cycle(0, self.sweeps);
        for (z, x) in z.iter_mut().zip(&mg.levels[0].x) {
            *z = f64::from(*x);
        }
    }
}
