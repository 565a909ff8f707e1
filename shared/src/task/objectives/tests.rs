use super::*;
use crate::material::Material;

fn palette() -> Palette {
    let mut muscle = Material::new("muscle", 1.0e5, 0.35);
    muscle.density = 1000.0;
    muscle.actuated = true;
    let mut bone = Material::new("bone", 1.0e7, 0.35);
    bone.density = 2000.0;
    Palette(vec![muscle, bone])
}

#[test]
fn the_hard_material_is_the_stiffest() {
    assert_eq!(stiffest(&palette()), 1);
    assert_eq!(stiffest(&Palette::hard_soft_resins()), 0);
    let equal = Palette(vec![
        Material::new("a", 1.0, 0.3),
        Material::new("b", 1.0, 0.3),
    ]);
    assert_eq!(stiffest(&equal), 0, "the lower index on a tie");
}

/// 3 muscle and 5 bone voxels of 1 cm: 3 · 1000 · 1e-6 + 5 · 2000 · 1e-6 = 0.013 kg; 3 of the 8
/// voxels actuate; bone fills 5 of the 40 cells of the workspace.
#[test]
fn mass_actuation_and_fractions_by_hand() {
    let counts = [3, 5];
    assert!((mass(&counts, &palette(), 0.01) - 0.013).abs() < 1e-15);
    assert_eq!(actuated_fraction(&counts, &palette()), 3.0 / 8.0);
    assert_eq!(actuated_fraction(&[0, 0], &palette()), 0.0);
    assert_eq!(fraction_of_cells(&counts, 1, 40), 5.0 / 40.0);
}

#[test]
fn a_maximized_objective_is_minimized_negated() {
    let speed = Objective {
        name: "speed",
        sense: Sense::Maximize,
        unit: "mm",
        about: "",
    };
    let voxels = Objective {
        sense: Sense::Minimize,
        ..speed
    };
    assert_eq!(speed.minimized(2.5), -2.5);
    assert_eq!(voxels.minimized(2.5), 2.5);
}
