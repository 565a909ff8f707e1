//! Every way building or solving a static model can fail, as one typed error.

use crate::material::MaterialError;

/// Errors of the static analysis. A design that cannot carry its load (empty, unsupported,
/// partly floating) is an error the caller turns into an evaluation outcome, never a panic.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StaticsError {
    #[error("the design has no filled voxel")]
    EmptyModel,
    #[error("voxel_size = {0} must be positive and finite")]
    InvalidVoxelSize(f64),
    #[error("palette: {0}")]
    Palette(#[from] MaterialError),
    #[error("cell {cell} uses material {material} but the palette holds {palette_len}")]
    UnknownMaterial {
        cell: usize,
        material: usize,
        palette_len: usize,
    },
    #[error("fixed_nodes is empty: nothing holds the structure")]
    NoFixedNode,
    #[error("{field}: node {node} is out of range (the model has {node_count} nodes)")]
    NodeOutOfRange {
        field: &'static str,
        node: usize,
        node_count: usize,
    },
    #[error("loads: component {component} on node {node} is {value}, not finite")]
    NonFiniteLoad {
        node: usize,
        component: usize,
        value: f64,
    },
    #[error(
        "{count} nodes (the first is node {first}) are not connected to any fixed node: the stiffness is singular"
    )]
    Unconnected { count: usize, first: usize },
    #[error(
        "pcg did not converge: relative residual {residual:e} after {iterations} iterations (tolerance {tolerance:e})"
    )]
    NotConverged {
        iterations: usize,
        residual: f64,
        tolerance: f64,
    },
    #[error("cholesky factorization failed: {0}")]
    Factorization(String),
    #[error("solver parameter {field} = {value} is out of range")]
    InvalidParameter { field: &'static str, value: f64 },
}

pub type Result<T> = std::result::Result<T, StaticsError>;
