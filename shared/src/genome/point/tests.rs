use super::*;

fn point() -> GaussianPoint {
    GaussianPoint {
        position: [0.5, 0.5, 0.5],
        density: 0.5,
        falloff: 0.1,
        material: MaterialId(0),
    }
}

#[test]
fn nan_is_rejected_naming_point_and_field() {
    let mut g = Genome::new(vec![point(), point()]);
    g.points[1].falloff = f64::NAN;
    let err = g.validate(&GenomeLimits::default(), 2).unwrap_err();
    assert_eq!(err.to_string(), "point 1: falloff = NaN is not finite");
}

#[test]
fn unknown_material_is_rejected() {
    let mut g = Genome::new(vec![point()]);
    g.points[0].material = MaterialId(3);
    assert!(matches!(
        g.validate(&GenomeLimits::default(), 2),
        Err(GenomeError::UnknownMaterial { point: 0, .. })
    ));
}

#[test]
fn oversized_genome_is_rejected() {
    let limits = GenomeLimits {
        max_points: 2,
        ..Default::default()
    };
    let g = Genome::new(vec![point(); 3]);
    assert!(matches!(
        g.validate(&limits, 1),
        Err(GenomeError::TooManyPoints { count: 3, max: 2 })
    ));
}

#[test]
fn position_outside_the_workspace_is_rejected() {
    let mut g = Genome::new(vec![point()]);
    g.points[0].position[1] = 1.5;
    let err = g.validate(&GenomeLimits::default(), 1).unwrap_err();
    assert!(err.to_string().starts_with("point 0: y = 1.5"), "{err}");
}
