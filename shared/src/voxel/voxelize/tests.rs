use super::*;
use crate::genome::GaussianPoint;

fn blob(position: [f64; 3], density: f64, material: u8) -> GaussianPoint {
    GaussianPoint {
        position,
        density,
        falloff: 0.15,
        material: MaterialId(material),
    }
}

#[test]
fn a_single_point_makes_a_centred_symmetric_blob() {
    let g = Genome::new(vec![blob([0.5, 0.5, 0.5], 1.0, 0)]);
    let grid = voxelize(&g, GridDims::new(10, 10, 10), 1, 0.5);
    assert!(grid.get(5, 5, 5).is_some());
    assert!(grid.get(0, 0, 0).is_none());
    for x in 0..10 {
        for y in 0..10 {
            for z in 0..10 {
                assert_eq!(grid.get(x, y, z), grid.get(9 - x, y, z));
                assert_eq!(grid.get(x, y, z), grid.get(x, z, y));
            }
        }
    }
}

#[test]
fn a_negative_point_carves_a_hole() {
    let solid = Genome::new(vec![blob([0.5, 0.5, 0.5], 1.0, 0)]);
    let mut carved = solid.clone();
    carved.points.push(GaussianPoint {
        falloff: 0.1,
        ..blob([0.5, 0.5, 0.5], -1.0, 0)
    });
    let dims = GridDims::new(10, 10, 10);
    assert!(
        voxelize(&carved, dims, 1, 0.5).filled_count()
            < voxelize(&solid, dims, 1, 0.5).filled_count()
    );
}

#[test]
fn each_voxel_takes_the_densest_material() {
    let g = Genome::new(vec![
        blob([0.2, 0.5, 0.5], 1.0, 0),
        blob([0.8, 0.5, 0.5], 1.0, 1),
    ]);
    let grid = voxelize(&g, GridDims::new(20, 10, 10), 2, 0.5);
    assert_eq!(grid.get(3, 5, 5), Some(MaterialId(0)));
    assert_eq!(grid.get(16, 5, 5), Some(MaterialId(1)));
}

#[test]
fn separable_fields_match_the_direct_sum() {
    let g = Genome::new(vec![
        blob([0.3, 0.6, 0.1], 0.7, 0),
        blob([0.9, 0.2, 0.4], -0.4, 0),
    ]);
    let dims = GridDims::new(4, 6, 8);
    let fields = density_fields(&g, dims, 1);
    let s = axis_scales(dims);
    assert_eq!(fields.len(), dims.cell_count());
    for (i, &field) in fields.iter().enumerate() {
        let [x, y, z] = dims.coords(i);
        let c = dims.normalized_centre(x, y, z);
        let direct: f64 = g
            .points
            .iter()
            .map(|p| {
                let d2: f64 = (0..3)
                    .map(|a| ((c[a] - p.position[a]) * s[a]).powi(2))
                    .sum();
                p.density * (-d2 / (2.0 * p.falloff * p.falloff)).exp()
            })
            .sum();
        assert!(
            (field - direct).abs() < 1e-12,
            "cell {i}: {field} vs {direct}"
        );
    }
}
