use super::*;

/// A rigid translation or an infinitesimal rigid rotation of a link produces no force: the
/// element's null space holds the six rigid-body modes (exact in floating point up to 1e-15
/// relative, as every entry is a small rational).
#[test]
fn rigid_body_modes_are_force_free() {
    let blocks = LinkBlocks::new();
    for axis in 0..3 {
        let k = [0, 1, 2].map(|w| blocks.block(axis, w, 1.0, 0.7));
        let kji = transpose(&k[1]);
        for mode in 0..6 {
            // node i at the origin, node j one voxel along +axis (scaled units: s = 1)
            let mut ui = [0.0; 6];
            let mut uj = [0.0; 6];
            if mode < 3 {
                ui[mode] = 1.0;
                uj[mode] = 1.0;
            } else {
                let w = mode - 3;
                ui[3 + w] = 1.0;
                uj[3 + w] = 1.0;
                // u_j = e_w × (e_axis): translation of node j by the rotation
                let mut e = [0.0; 3];
                e[axis] = 1.0;
                let mut rot = [0.0; 3];
                rot[w] = 1.0;
                uj[0] = rot[1] * e[2] - rot[2] * e[1];
                uj[1] = rot[2] * e[0] - rot[0] * e[2];
                uj[2] = rot[0] * e[1] - rot[1] * e[0];
            }
            for r in 0..6 {
                let fi: f64 = (0..6)
                    .map(|c| k[0][6 * r + c] * ui[c] + k[1][6 * r + c] * uj[c])
                    .sum();
                let fj: f64 = (0..6)
                    .map(|c| kji[6 * r + c] * ui[c] + k[2][6 * r + c] * uj[c])
                    .sum();
                assert!(
                    fi.abs() < 1e-15 && fj.abs() < 1e-15,
                    "axis {axis} mode {mode} row {r}"
                );
            }
        }
    }
}

#[test]
fn diagonal_blocks_are_symmetric() {
    let blocks = LinkBlocks::new();
    for axis in 0..3 {
        for w in [0, 2] {
            let b = blocks.block(axis, w, 1.3, 0.4);
            assert_eq!(b, transpose(&b));
        }
    }
}
