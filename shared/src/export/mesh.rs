//! The closed, oriented boundary surface of a set of voxels, as a triangle mesh.
//!
//! Every face between a voxel of the set and a cell outside it becomes two triangles, wound
//! counter-clockwise seen from outside. Where voxels of the set touch only along an edge or at a
//! corner, the boundary of their union is not a manifold (four faces meet at one edge); slicers and
//! the manifold test both want two. We resolve it as a 6-connected solid: at such an edge the two
//! faces of the same voxel are paired, and the lattice point gets one vertex per group of faces
//! that pairing joins around it, each pulled `PINCH_OFFSET` of a voxel towards its own voxels, so
//! the sheets are distinct in space too (STL identifies vertices by position). The volume changes
//! by O(`PINCH_OFFSET`) voxel volumes per pinch.

use std::collections::BTreeMap;

use crate::material::MaterialId;
use crate::voxel::VoxelGrid;

/// How far, in voxel sizes, a split vertex is pulled towards its own voxels.
pub const PINCH_OFFSET: f64 = 1e-3;

/// An indexed triangle mesh; triangles wind counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Enclosed volume by the divergence theorem (positive for outward winding).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }

    /// Scales every vertex (e.g. metres to millimetres).
    pub fn scaled(mut self, factor: f64) -> Self {
        for v in &mut self.vertices {
            *v = v.map(|c| c * factor);
        }
        self
    }
}

/// One exposed voxel face: the cell, the axis and whether it faces +axis.
#[derive(Clone, Copy, Debug)]
struct Face {
    cell: [usize; 3],
    /// The cell outside the face (may lie outside the grid).
    outside: [isize; 3],
    corners: [[usize; 3]; 4],
}

/// The boundary of the voxels selected by `member` (a cell index → in the set), in metres with
/// voxel size `voxel_size` and the grid's corner at the origin: two triangles per voxel face.
pub fn boundary_mesh(
    grid: &VoxelGrid,
    voxel_size: f64,
    member: impl Fn(Option<MaterialId>) -> bool,
) -> TriangleMesh {
    let surface = boundary_surface(grid, voxel_size, member);
    let mut mesh = TriangleMesh {
        vertices: surface.vertices,
        triangles: Vec::with_capacity(2 * surface.faces.len()),
    };
    for face in &surface.faces {
        let v = face.vertices;
        mesh.triangles.push([v[0], v[1], v[2]]);
        mesh.triangles.push([v[0], v[2], v[3]]);
    }
    mesh
}

/// One exposed voxel face of a [`BoundarySurface`].
#[derive(Clone, Copy, Debug)]
pub(super) struct SurfaceFace {
    pub cell: [usize; 3],
    /// The face's normal is +axis (`positive`) or −axis.
    pub axis: usize,
    pub positive: bool,
    /// Corner vertices, counter-clockwise seen from outside, as [`face_corners`] orders them.
    pub vertices: [u32; 4],
}

/// The boundary as voxel faces over shared vertices (metres), before triangulation.
#[derive(Clone, Debug)]
pub(super) struct BoundarySurface {
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<SurfaceFace>,
    /// Per vertex: whether its lattice point was split at a pinch (and the vertex moved off it).
    pub pinched: Vec<bool>,
    pub voxel_size: f64,
}

/// The faces and vertices of [`boundary_mesh`], pinches resolved.
pub(super) fn boundary_surface(
    grid: &VoxelGrid,
    voxel_size: f64,
    member: impl Fn(Option<MaterialId>) -> bool,
) -> BoundarySurface {
    let dims = grid.dims();
    let n = [dims.nx, dims.ny, dims.nz];
    let inside = |c: [isize; 3]| {
        (0..3).all(|a| c[a] >= 0 && (c[a] as usize) < n[a])
            && member(grid.get(c[0] as usize, c[1] as usize, c[2] as usize))
    };

    let mut faces = Vec::new();
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                let cell = [x, y, z];
                if !inside(cell.map(|c| c as isize)) {
                    continue;
                }
                for axis in 0..3 {
                    for positive in [false, true] {
                        let mut next = cell.map(|c| c as isize);
                        next[axis] += if positive { 1 } else { -1 };
                        if !inside(next) {
                            faces.push(Face {
                                cell,
                                outside: next,
                                corners: face_corners(cell, axis, positive),
                            });
                        }
                    }
                }
            }
        }
    }

    // Pair the faces along every lattice edge; a face-corner is (face, corner index).
    let point_key = |p: [usize; 3]| p[0] + (n[0] + 1) * (p[1] + (n[1] + 1) * p[2]);
    let mut edges: BTreeMap<(usize, usize), Vec<(usize, usize)>> = BTreeMap::new();
    for (f, face) in faces.iter().enumerate() {
        for k in 0..4 {
            let (p, q) = (
                point_key(face.corners[k]),
                point_key(face.corners[(k + 1) % 4]),
            );
            edges.entry((p.min(q), p.max(q))).or_default().push((f, k));
        }
    }
    let mut classes = UnionFind::new(4 * faces.len());
    for sharing in edges.values() {
        // Two faces: a manifold edge. Four: two voxels of the set touching along the edge only,
        // two outside cells likewise. Pair the faces of the same voxel (the 6-connected reading)
        // unless the two voxels are joined through the set around both ends of the edge: then
        // the set wraps the two outside cells, and pairing by voxel would meet again at both
        // ends; pair the faces of the same outside cell instead.
        let mut pairs: Vec<[(usize, usize); 2]> = Vec::new();
        if sharing.len() == 2 {
            pairs.push([sharing[0], sharing[1]]);
        } else {
            let (f0, k0) = sharing[0];
            let a = faces[f0].cell;
            let b = sharing
                .iter()
                .map(|&(g, _)| faces[g].cell)
                .find(|&c| c != a)
                .unwrap_or(a);
            let ends = [faces[f0].corners[k0], faces[f0].corners[(k0 + 1) % 4]];
            let by_outside = ends.iter().all(|&p| joined_around(p, a, b, &inside));
            let mut rest = sharing.clone();
            while let Some(first) = rest.pop() {
                let same = |g: usize| {
                    if by_outside {
                        faces[g].outside == faces[first.0].outside
                    } else {
                        faces[g].cell == faces[first.0].cell
                    }
                };
                if let Some(i) = rest.iter().position(|&(g, _)| same(g)) {
                    pairs.push([first, rest.remove(i)]);
                }
            }
        }
        for [(f, k), (g, l)] in pairs {
            // Edge k of face f runs corner k → k+1; the paired face runs it the other way.
            let (f_start, f_end) = (4 * f + k, 4 * f + (k + 1) % 4);
            let (g_start, g_end) = (4 * g + l, 4 * g + (l + 1) % 4);
            classes.union(f_start, g_end);
            classes.union(f_end, g_start);
        }
    }

    // One vertex per class, and the triangles; a lattice point with several vertices is a pinch:
    // pull each towards the voxels of its faces.
    let mut vertex_of_root = vec![u32::MAX; 4 * faces.len()];
    let mut centre_sum: Vec<([f64; 3], usize)> = Vec::new();
    let mut vertices_at_point: BTreeMap<usize, usize> = BTreeMap::new();
    let mut point_of_vertex = Vec::new();
    let mut mesh = TriangleMesh::default();
    let mut surface_faces = Vec::with_capacity(faces.len());
    for (f, face) in faces.iter().enumerate() {
        let mut v = [0u32; 4];
        for (k, vk) in v.iter_mut().enumerate() {
            let root = classes.find(4 * f + k);
            if vertex_of_root[root] == u32::MAX {
                vertex_of_root[root] = mesh.vertices.len() as u32;
                mesh.vertices.push(face.corners[k].map(|c| c as f64));
                centre_sum.push(([0.0; 3], 0));
                let point = point_key(face.corners[k]);
                *vertices_at_point.entry(point).or_default() += 1;
                point_of_vertex.push(point);
            }
            *vk = vertex_of_root[root];
            let sum = &mut centre_sum[*vk as usize];
            for a in 0..3 {
                sum.0[a] += face.cell[a] as f64 + 0.5;
            }
            sum.1 += 1;
        }
        let axis = (0..3)
            .find(|&a| face.outside[a] != face.cell[a] as isize)
            .unwrap_or(0);
        surface_faces.push(SurfaceFace {
            cell: face.cell,
            axis,
            positive: face.outside[axis] > face.cell[axis] as isize,
            vertices: v,
        });
    }
    let mut pinched = vec![false; mesh.vertices.len()];
    for (v, position) in mesh.vertices.iter_mut().enumerate() {
        if vertices_at_point[&point_of_vertex[v]] > 1 {
            pinched[v] = true;
            let (sum, count) = centre_sum[v];
            for a in 0..3 {
                position[a] += PINCH_OFFSET * (sum[a] / count as f64 - position[a]);
            }
        }
        *position = position.map(|c| c * voxel_size);
    }
    BoundarySurface {
        vertices: mesh.vertices,
        faces: surface_faces,
        pinched,
        voxel_size,
    }
}

/// The four corners of a cell's face, counter-clockwise seen from outside: with (u, v) the next
/// two axes cyclically, u × v is +axis, so the + face runs p, p+u, p+u+v, p+v and the − face the
/// reverse.
fn face_corners(cell: [usize; 3], axis: usize, positive: bool) -> [[usize; 3]; 4] {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut p = cell;
    if positive {
        p[axis] += 1;
    }
    let shift = |mut q: [usize; 3], du: usize, dv: usize| {
        q[u] += du;
        q[v] += dv;
        q
    };
    if positive {
        [p, shift(p, 1, 0), shift(p, 1, 1), shift(p, 0, 1)]
    } else {
        [p, shift(p, 0, 1), shift(p, 1, 1), shift(p, 1, 0)]
    }
}

/// Whether cells `a` and `b` are face-connected through cells of the set within the 2×2×2 block
/// of cells around lattice point `p`.
fn joined_around(
    p: [usize; 3],
    a: [usize; 3],
    b: [usize; 3],
    inside: &impl Fn([isize; 3]) -> bool,
) -> bool {
    let block: Vec<[isize; 3]> = (0..8)
        .map(|k| {
            [
                p[0] as isize - 1 + (k & 1) as isize,
                p[1] as isize - 1 + ((k >> 1) & 1) as isize,
                p[2] as isize - 1 + (k >> 2) as isize,
            ]
        })
        .filter(|&c| inside(c))
        .collect();
    let (a, b) = (a.map(|c| c as isize), b.map(|c| c as isize));
    let mut reached = vec![a];
    let mut frontier = vec![a];
    while let Some(c) = frontier.pop() {
        for &d in &block {
            let distance: isize = (0..3).map(|i| (c[i] - d[i]).abs()).sum();
            if distance == 1 && !reached.contains(&d) {
                reached.push(d);
                frontier.push(d);
            }
        }
    }
    reached.contains(&b)
}

/// Disjoint sets over face-corners, path-halving and union by index (deterministic roots).
struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}
