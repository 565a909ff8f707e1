//! The direct path: faer's sparse Cholesky (AMD ordering, supernodal) of a block matrix.

use faer::MatMut;
use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};

use super::bsr::BlockMatrix;
use super::error::{Result, StaticsError};

/// A numeric Cholesky factor `L Lᵀ` of an SPD block matrix.
#[derive(Debug)]
pub(crate) struct DirectFactor {
    llt: Llt<usize, f64>,
}

impl DirectFactor {
    /// Factors `matrix` (its upper triangle is read).
    pub fn new(matrix: &BlockMatrix) -> Result<Self> {
        let upper = upper_triangle_csc(matrix);
        let symbolic = SymbolicLlt::try_new(upper.symbolic(), Side::Upper)
            .map_err(|e| StaticsError::Factorization(format!("{e:?}")))?;
        let llt = Llt::try_new_with_symbolic(symbolic, upper.as_ref(), Side::Upper)
            .map_err(|e| StaticsError::Factorization(e.to_string()))?;
        Ok(Self { llt })
    }

    /// Overwrites `rhs` with the solution.
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        let n = rhs.len();
        let view = MatMut::from_column_major_slice_mut(rhs, n, 1);
        self.llt.solve_in_place(view);
    }
}

/// The upper triangle of a symmetric block matrix as a scalar CSC matrix. Column j of the upper
/// triangle is row j restricted to columns ≤ j, so it is read from the block row.
fn upper_triangle_csc(matrix: &BlockMatrix) -> SparseColMat<usize, f64> {
    let dof = matrix.dof();
    let mut col_ptr = Vec::with_capacity(dof + 1);
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    col_ptr.push(0);
    for block_row in 0..matrix.n {
        let (cols, blocks) = matrix.row(block_row);
        for local_col in 0..6 {
            let col = 6 * block_row + local_col;
            for (&bc, b) in cols.iter().zip(blocks) {
                let bc = bc as usize;
                if bc > block_row {
                    break;
                }
                for local_row in 0..6 {
                    let row = 6 * bc + local_row;
                    if row > col {
                        break;
                    }
                    // K[row][col] = K[col][row], which lives in block (block_row, bc)
                    row_idx.push(row);
                    values.push(b[6 * local_col + local_row]);
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    let symbolic = SymbolicSparseColMat::new_checked(dof, dof, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}
