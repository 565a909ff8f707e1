use super::*;

#[test]
fn the_scaled_period_keeps_the_dynamic_actuation_force() {
    let evolved = PhysicalBuild {
        voxel_size: 1e-3,
        density: 500.0,
    };
    for to in [
        PhysicalBuild {
            voxel_size: 1e-3,
            density: 500.0,
        },
        PhysicalBuild {
            voxel_size: 6.35e-3,
            density: 90.0,
        },
        PhysicalBuild {
            voxel_size: 0.05,
            density: 1200.0,
        },
    ] {
        let period = equivalent_actuation_period(0.07, evolved, to);
        let before = dynamic_actuation_force(evolved, 3544, 0.0627, 0.07);
        let after = dynamic_actuation_force(to, 3544, 0.0627, period);
        assert!(
            (after - before).abs() <= 1e-12 * before,
            "{before} vs {after}"
        );
    }
    // Twice the size in the same material: four times the period.
    let twice = PhysicalBuild {
        voxel_size: 2e-3,
        density: 500.0,
    };
    assert!((equivalent_actuation_period(0.07, evolved, twice) - 0.28).abs() < 1e-15);
}
