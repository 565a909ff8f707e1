//! Smooth surfaces of a design. The genome is a continuous density field, so instead of voxel
//! faces each material's region can be meshed as a level set of that field at a finer sampling:
//! marching tetrahedra over the sample lattice.
//!
//! Why tetrahedra and not marching cubes: every cube of samples is split into the six Kuhn
//! tetrahedra around its main diagonal, which tile space consistently between neighbouring cubes.
//! Inside one tetrahedron the field is interpolated linearly, so its zero set is one flat triangle
//! or quad, and the surface of the piecewise-linear field is a closed 2-manifold by construction
//! (no ambiguous cases, no case table). Its vertices sit on lattice edges, shared by every
//! tetrahedron around the edge, so welding them by edge gives an indexed mesh with each edge in
//! exactly two triangles.

use std::collections::HashMap;

use super::mesh::TriangleMesh;
use crate::genome::Genome;
use crate::task::Scene;
use crate::voxel::{GridDims, VoxelGrid, density_fields};

/// A sampled field is inside where its value is above zero (zero itself counts as outside, so
/// every sample has a side and no vertex lies exactly on the surface).
#[derive(Clone, Debug, PartialEq)]
pub struct SampledField {
    /// Samples along x, y and z.
    pub counts: [usize; 3],
    /// `values[i + nx (j + ny k)]`.
    pub values: Vec<f64>,
}

/// Keeps mesh vertices at least this fraction of a lattice edge away from its samples, so a
/// sample lying exactly on the level set cannot make several vertices share one position (STL
/// identifies vertices by position). Moves the surface by at most 1e-3 sample spacings.
const VERTEX_CLEARANCE: f64 = 1e-3;

/// The six tetrahedra of a cube as paths from corner (0,0,0) to (1,1,1), one per order of the
/// axes: each step adds one unit vector. Shared faces of neighbouring cubes are split along the
/// same diagonal, so the tetrahedra tile space.
const KUHN_ORDERS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];

/// The closed surface where `field` crosses zero, sample (i, j, k) placed at
/// `origin + spacing · (i, j, k)`, triangles wound counter-clockwise seen from outside.
///
/// Beyond the lattice the field is continued by one layer of samples half a spacing out, with
/// value 0 (outside, but only just): a region reaching the last samples is closed by a flat cap
/// through that layer, which for samples at cell centres is the workspace boundary. The cap's
/// vertices sit `VERTEX_CLEARANCE` of their edge inside it.
pub fn isosurface(field: &SampledField, origin: [f64; 3], spacing: f64) -> TriangleMesh {
    let n = field.counts;
    // Padded lattice: one layer on each side; padded index 1 is sample 0.
    let p = n.map(|c| c + 2);
    let padded_index = |q: [usize; 3]| q[0] + p[0] * (q[1] + p[1] * q[2]);
    let mut values = vec![0.0; p[0] * p[1] * p[2]];
    for k in 1..=n[2] {
        for j in 1..=n[1] {
            for i in 1..=n[0] {
                values[padded_index([i, j, k])] =
                    field.values[(i - 1) + n[0] * ((j - 1) + n[1] * (k - 1))];
            }
        }
    }
    // Position along an axis of padded index q: the pad layers half a spacing out.
    let coordinate = |axis: usize, q: usize| {
        let q = if q == 0 {
            0.5
        } else if q == p[axis] - 1 {
            q as f64 - 0.5
        } else {
            q as f64
        };
        origin[axis] + spacing * (q - 1.0)
    };

    let mut mesh = TriangleMesh::default();
    let mut vertex_of_edge: HashMap<(usize, usize), u32> = HashMap::new();
    for k in 0..p[2] - 1 {
        for j in 0..p[1] - 1 {
            for i in 0..p[0] - 1 {
                for order in KUHN_ORDERS {
                    let mut corners = [[i, j, k]; 4];
                    for step in 0..3 {
                        corners[step + 1] = corners[step];
                        corners[step + 1][order[step]] += 1;
                    }
                    let tet = corners.map(|c| (padded_index(c), c));
                    let mut vertex = |a: usize, b: usize| {
                        let ((ia, ca), (ib, cb)) = (tet[a], tet[b]);
                        *vertex_of_edge
                            .entry((ia.min(ib), ia.max(ib)))
                            .or_insert_with(|| {
                                // a inside, b outside: f crosses zero at t = fa / (fa − fb).
                                let (fa, fb) = (values[ia], values[ib]);
                                let t = (fa / (fa - fb))
                                    .clamp(VERTEX_CLEARANCE, 1.0 - VERTEX_CLEARANCE);
                                let position = [0, 1, 2].map(|ax| {
                                    let (xa, xb) = (coordinate(ax, ca[ax]), coordinate(ax, cb[ax]));
                                    xa + t * (xb - xa)
                                });
                                mesh.vertices.push(position);
                                (mesh.vertices.len() - 1) as u32
                            })
                    };
                    let inside = tet.map(|(index, _)| values[index] > 0.0);
                    let inner: Vec<usize> = (0..4).filter(|&v| inside[v]).collect();
                    let outer: Vec<usize> = (0..4).filter(|&v| !inside[v]).collect();
                    let triangles: Vec<[u32; 3]> = match (inner.as_slice(), outer.as_slice()) {
                        ([a], [b, c, d]) => vec![[vertex(*a, *b), vertex(*a, *c), vertex(*a, *d)]],
                        ([a, b, c], [d]) => vec![[vertex(*a, *d), vertex(*b, *d), vertex(*c, *d)]],
                        ([a, b], [c, d]) => {
                            // The quad a–c, a–d, b–d, b–c, in order around its border.
                            let q = [
                                vertex(*a, *c),
                                vertex(*a, *d),
                                vertex(*b, *d),
                                vertex(*b, *c),
                            ];
                            vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                        }
                        _ => Vec::new(),
                    };
                    if triangles.is_empty() {
                        continue;
                    }
                    // Outward is from the inside corners towards the outside ones: for a linear
                    // field that is −∇f, whatever the triangle's vertex order came out as.
                    let centroid = |of: &[usize]| {
                        let mut c = [0.0; 3];
                        for &v in of {
                            for (ax, value) in c.iter_mut().enumerate() {
                                *value += coordinate(ax, tet[v].1[ax]) / of.len() as f64;
                            }
                        }
                        c
                    };
                    let (ci, co) = (centroid(&inner), centroid(&outer));
                    let outward = [0, 1, 2].map(|ax| co[ax] - ci[ax]);
                    for t in triangles {
                        let [a, b, c] = t.map(|v| mesh.vertices[v as usize]);
                        let normal = cross(sub(b, a), sub(c, a));
                        let facing = (0..3).map(|ax| normal[ax] * outward[ax]).sum::<f64>();
                        mesh.triangles
                            .push(if facing >= 0.0 { t } else { [t[0], t[2], t[1]] });
                    }
                }
            }
        }
    }
    mesh
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// How finely to sample a design of `dims` so the longest side gets about `samples_longest`
/// samples: a whole number of samples per voxel (at least one), so the samples keep the
/// design's aspect ratio exactly and one per voxel reproduces the voxelization's samples.
pub fn samples_per_voxel(dims: GridDims, samples_longest: usize) -> usize {
    let longest = dims.nx.max(dims.ny).max(dims.nz);
    ((samples_longest as f64 / longest as f64).round() as usize).max(1)
}

/// The smooth surface of each material's region of `genome` in `scene` (index = material id; an
/// absent material gets an empty mesh), in millimetres in the frame of the voxel STL files,
/// sampled `samples_per_voxel` times per voxel of `dims` along each axis.
///
/// Material k's region is where the total density is above the scene's threshold and k is the
/// densest material, the voxelization's own rule, as one field: min(Σρ − threshold,
/// ρ_k − max_{j≠k} ρ_j). Like the voxel design it keeps only what the task uses: samples farther
/// than one voxel from every kept voxel (a clamp-disconnected part of a beam, a robot's smaller
/// bodies) count as outside.
pub fn smooth_material_meshes(
    genome: &Genome,
    scene: &Scene,
    dims: GridDims,
    samples_per_voxel: usize,
) -> Vec<TriangleMesh> {
    let r = samples_per_voxel.max(1);
    let sample_dims = GridDims::new(dims.nx * r, dims.ny * r, dims.nz * r);
    let materials = scene.palette().len();
    let threshold = scene.threshold();
    let fields = density_fields(genome, sample_dims, materials);
    let kept = near_design(&scene.design(genome, dims));
    let cells = sample_dims.cell_count();
    let voxel_mm = 1e3 * scene.voxel_size(dims);
    let spacing = voxel_mm / r as f64;
    // Sample (i, j, k) is the centre of fine cell (i, j, k).
    let origin = [0.5 * spacing; 3];
    (0..materials)
        .map(|m| {
            let values = (0..cells)
                .map(|i| {
                    let [x, y, z] = sample_dims.coords(i);
                    let mut total = 0.0;
                    let mut others = f64::NEG_INFINITY;
                    for k in 0..materials {
                        let rho = fields[k * cells + i];
                        total += rho;
                        if k != m {
                            others = others.max(rho);
                        }
                    }
                    let own = fields[m * cells + i];
                    let value = (total - threshold).min(own - others);
                    if kept[dims.index(x / r, y / r, z / r)] {
                        value
                    } else {
                        -value.abs()
                    }
                })
                .collect();
            let field = SampledField {
                counts: [sample_dims.nx, sample_dims.ny, sample_dims.nz],
                values,
            };
            isosurface(&field, origin, spacing)
        })
        .collect()
}

/// Per cell: whether it or one of its 26 neighbours is filled in `design`.
fn near_design(design: &VoxelGrid) -> Vec<bool> {
    let d = design.dims();
    let mut near = vec![false; d.cell_count()];
    for i in design.filled_indices() {
        for n in d.neighbourhood(i) {
            near[n] = true;
        }
    }
    near
}
