//! Fewer triangles for the voxel surface: coplanar voxel faces merged into rectangles, without
//! T-junctions.
//!
//! Merging faces greedily into rectangles per plane is easy; keeping the mesh watertight is not:
//! a rectangle's long side runs past the corners of the rectangles and faces beside it (in its
//! own plane, or across the crease in another plane), and a vertex lying on another triangle's
//! edge (a T-junction) leaves that edge used once, so the surface is no longer closed. Here every
//! rectangle's border is split at each rectangle corner lying on it, so a stretch of border
//! between two such points is matched exactly by the neighbour's stretch, and the polygon is
//! fanned from a new vertex at its centre (a fan from a corner would make zero-area triangles
//! along the collinear points). A rectangle's interior lattice points are touched by no other
//! face, so they drop out.
//!
//! Faces with a corner at a pinch (where the mesh split a lattice point and moved the vertices
//! off it) are left as they are, two triangles each: their corners are not on the lattice.

use std::collections::{HashMap, HashSet};

use super::mesh::{BoundarySurface, SurfaceFace, TriangleMesh};

/// An axis-aligned rectangle of `width × height` faces in one plane, `first` its lowest face.
#[derive(Clone, Copy, Debug)]
struct Rectangle {
    first: SurfaceFace,
    width: usize,
    height: usize,
}

/// Triangulates `surface` with coplanar faces merged; same closed surface, same volume.
pub(super) fn merged_mesh(surface: &BoundarySurface) -> TriangleMesh {
    let (rectangles, singles) = rectangles(surface);

    // The lattice points where borders must be split: every rectangle's and single face's corners.
    let mut corners: HashSet<[usize; 3]> = HashSet::new();
    let mut vertex_at: HashMap<[usize; 3], u32> = HashMap::new();
    for face in &surface.faces {
        let lattice = face_lattice_corners(face);
        if !face.vertices.iter().any(|&v| surface.pinched[v as usize]) {
            for (point, &v) in lattice.iter().zip(&face.vertices) {
                vertex_at.insert(*point, v);
            }
        }
    }
    for face in &singles {
        corners.extend(face_lattice_corners(face));
    }
    for r in &rectangles {
        corners.extend(
            rectangle_border(r)
                .into_iter()
                .filter(|&(_, corner)| corner)
                .map(|(p, _)| p),
        );
    }

    let mut mesh = TriangleMesh {
        vertices: surface.vertices.clone(),
        triangles: Vec::new(),
    };
    for face in &singles {
        let v = face.vertices;
        mesh.triangles.push([v[0], v[1], v[2]]);
        mesh.triangles.push([v[0], v[2], v[3]]);
    }
    for r in &rectangles {
        let border: Vec<u32> = rectangle_border(r)
            .into_iter()
            .filter(|(p, corner)| *corner || corners.contains(p))
            .map(|(p, _)| vertex_at[&p])
            .collect();
        if border.len() == 4 {
            mesh.triangles.push([border[0], border[1], border[2]]);
            mesh.triangles.push([border[0], border[2], border[3]]);
            continue;
        }
        let centre = mesh.vertices.len() as u32;
        mesh.vertices.push(rectangle_centre(r, surface.voxel_size));
        for k in 0..border.len() {
            mesh.triangles
                .push([centre, border[k], border[(k + 1) % border.len()]]);
        }
    }
    drop_unused_vertices(mesh)
}

/// A plane of faces: normal axis, facing +axis or not, and the cell coordinate along the axis.
type PlaneKey = (usize, bool, usize);

/// Greedy rectangles per plane over the faces with no pinched corner (row by row: widest run
/// along u, then as many full rows along v as fit), and the faces left single.
fn rectangles(surface: &BoundarySurface) -> (Vec<Rectangle>, Vec<SurfaceFace>) {
    let mut singles = Vec::new();
    let mut planes: HashMap<PlaneKey, HashMap<(usize, usize), SurfaceFace>> = HashMap::new();
    for face in &surface.faces {
        if face.vertices.iter().any(|&v| surface.pinched[v as usize]) {
            singles.push(*face);
            continue;
        }
        let (u, v) = uv(face);
        planes
            .entry((face.axis, face.positive, face.cell[face.axis]))
            .or_default()
            .insert((face.cell[u], face.cell[v]), *face);
    }
    let mut keys: Vec<_> = planes.keys().copied().collect();
    keys.sort_unstable();
    let mut rectangles = Vec::new();
    for key in keys {
        let plane = &planes[&key];
        let mut cells: Vec<(usize, usize)> = plane.keys().copied().collect();
        cells.sort_unstable_by_key(|&(u, v)| (v, u));
        let mut taken: HashSet<(usize, usize)> = HashSet::new();
        let free = |c: (usize, usize), taken: &HashSet<(usize, usize)>| {
            plane.contains_key(&c) && !taken.contains(&c)
        };
        for (u0, v0) in cells {
            if taken.contains(&(u0, v0)) {
                continue;
            }
            let mut width = 1;
            while free((u0 + width, v0), &taken) {
                width += 1;
            }
            let mut height = 1;
            while (0..width).all(|du| free((u0 + du, v0 + height), &taken)) {
                height += 1;
            }
            for dv in 0..height {
                for du in 0..width {
                    taken.insert((u0 + du, v0 + dv));
                }
            }
            rectangles.push(Rectangle {
                first: plane[&(u0, v0)],
                width,
                height,
            });
        }
    }
    (rectangles, singles)
}

/// The two in-plane axes of a face, in the order [`face_lattice_corners`] walks them.
fn uv(face: &SurfaceFace) -> (usize, usize) {
    ((face.axis + 1) % 3, (face.axis + 2) % 3)
}

/// A face's corner lattice points in the order of its vertices (counter-clockwise from outside):
/// on a + face p, p+u, p+u+v, p+v; on a − face the reverse way round.
fn face_lattice_corners(face: &SurfaceFace) -> [[usize; 3]; 4] {
    let r = Rectangle {
        first: *face,
        width: 1,
        height: 1,
    };
    let border = rectangle_border(&r);
    [0, 1, 2, 3].map(|k| border[k].0)
}

/// Every lattice point on a rectangle's border, counter-clockwise seen from outside starting at
/// its lowest corner, each marked whether it is one of the four corners.
fn rectangle_border(r: &Rectangle) -> Vec<([usize; 3], bool)> {
    let face = &r.first;
    let (u, v) = uv(face);
    let mut base = face.cell;
    if face.positive {
        base[face.axis] += 1;
    }
    let at = |du: usize, dv: usize| {
        let mut p = base;
        p[u] += du;
        p[v] += dv;
        p
    };
    let (w, h) = (r.width, r.height);
    // + face: along +u, then +v, then −u, then −v.
    let mut walk: Vec<([usize; 3], bool)> = Vec::with_capacity(2 * (w + h));
    for du in 0..w {
        walk.push((at(du, 0), du == 0));
    }
    for dv in 0..h {
        walk.push((at(w, dv), dv == 0));
    }
    for du in (1..=w).rev() {
        walk.push((at(du, h), du == w));
    }
    for dv in (1..=h).rev() {
        walk.push((at(0, dv), dv == h));
    }
    if !face.positive {
        // − face: the same loop the other way round, still starting at the lowest corner.
        walk[1..].reverse();
    }
    walk
}

fn rectangle_centre(r: &Rectangle, voxel_size: f64) -> [f64; 3] {
    let face = &r.first;
    let (u, v) = uv(face);
    let mut c = [0.0; 3];
    c[face.axis] = (face.cell[face.axis] + usize::from(face.positive)) as f64;
    c[u] = face.cell[u] as f64 + 0.5 * r.width as f64;
    c[v] = face.cell[v] as f64 + 0.5 * r.height as f64;
    c.map(|x| x * voxel_size)
}

/// Removes vertices no triangle uses (the merged rectangles' interior points), keeping order.
fn drop_unused_vertices(mesh: TriangleMesh) -> TriangleMesh {
    let mut new_index = vec![u32::MAX; mesh.vertices.len()];
    let mut vertices = Vec::new();
    let mut triangles = mesh.triangles;
    for t in &mut triangles {
        for v in t.iter_mut() {
            let i = *v as usize;
            if new_index[i] == u32::MAX {
                new_index[i] = vertices.len() as u32;
                vertices.push(mesh.vertices[i]);
            }
            *v = new_index[i];
        }
    }
    TriangleMesh {
        vertices,
        triangles,
    }
}
