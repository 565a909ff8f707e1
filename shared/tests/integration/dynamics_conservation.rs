//! Conservation and reproducibility: a free body in rigid motion keeps its shape, momentum and
//! angular momentum; the same scene twice gives bit-identical trajectories.

use amorph::dynamics::{Actuation, DynamicScene, Simulation, Vec3, foam_palette};
use amorph::material::{Material, MaterialId, Palette};
use amorph::voxel::{GridDims, VoxelGrid};

fn rubber() -> Palette {
    Palette(vec![Material::new("rubber", 1.0e6, 0.35)])
}

fn relative(a: Vec3, b: Vec3) -> f64 {
    (a - b).norm() / b.norm()
}

#[test]
fn free_rigid_motion_keeps_shape_and_momenta() {
    let grid = VoxelGrid::filled(GridDims::new(3, 4, 2), MaterialId(0));
    // Link damping on: it must not damp rigid motion (it acts on relative motion only).
    let scene = DynamicScene {
        damping: amorph::dynamics::DampingParams {
            link: 1.0,
            global: 0.0,
            contact: 0.0,
        },
        ..DynamicScene::free_space(0.01)
    };
    let mut sim = Simulation::new(&grid, &rubber(), &scene).unwrap();
    let centre = sim.centre_of_mass();
    sim.set_rigid_velocity(Vec3::new(0.3, -0.2, 0.1), Vec3::new(1.0, 2.0, -0.5), centre);
    let (p0, l0, k0) = (
        sim.linear_momentum(),
        sim.angular_momentum(),
        sim.energy().kinetic,
    );
    let distances = |sim: &Simulation| {
        let x = sim.positions();
        let mut d = Vec::new();
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                d.push((x[i] - x[j]).norm());
            }
        }
        d
    };
    let d0 = distances(&sim);
    sim.run_steps(10_000).unwrap();
    eprintln!(
        "relative change: momentum {:.2e}, angular momentum {:.2e}",
        relative(sim.linear_momentum(), p0),
        relative(sim.angular_momentum(), l0)
    );
    // Links act in equal and opposite pairs and every link's moments balance its force couple
    // exactly, so only round-off changes the momenta: the bound is 1e-9 over 1e4 steps.
    assert!(relative(sim.linear_momentum(), p0) < 1e-9);
    assert!(relative(sim.angular_momentum(), l0) < 1e-9);
    // The body turned by ~1 rad; the centripetal load strains the links by ω²r·m/k ~ 1e-7, so
    // pairwise distances hold to 1e-5 relative if the rotation is handled without distortion.
    let d1 = distances(&sim);
    let shape_error = d0
        .iter()
        .zip(&d1)
        .map(|(a, b)| (a - b).abs() / a)
        .fold(0.0, f64::max);
    eprintln!("shape error {shape_error:.2e}");
    assert!(shape_error < 1e-5, "shape error {shape_error}");
    // Rigid kinetic energy is not dissipated by link damping (only the tiny elastic breathing).
    let k1 = sim.energy().kinetic;
    eprintln!("kinetic energy change {:.2e}", (k1 - k0).abs() / k0);
    assert!((k1 - k0).abs() / k0 < 1e-4, "kinetic {k0} -> {k1}");
}

fn trajectory() -> Vec<Vec3> {
    let mut cells = vec![None; 6 * 4 * 3];
    let dims = GridDims::new(6, 4, 3);
    for z in 0..3 {
        for y in 0..4 {
            for x in 0..6 {
                if z < 2 || x % 2 == 0 {
                    cells[dims.index(x, y, z)] = Some(MaterialId(u8::from(x < 3)));
                }
            }
        }
    }
    let grid = VoxelGrid::from_cells(dims, cells);
    let scene = DynamicScene {
        collisions: true,
        actuation: Some(Actuation {
            period: 0.01,
            ..Actuation::default()
        }),
        ..DynamicScene::paper_locomotion()
    };
    let mut sim = Simulation::new(&grid, &foam_palette(), &scene).unwrap();
    sim.start_actuation();
    let mut trace = Vec::new();
    for _ in 0..20 {
        sim.run_steps(200).unwrap();
        trace.extend_from_slice(sim.positions());
    }
    trace
}

#[test]
fn same_scene_twice_is_bit_identical() {
    // Every pass on (floor, friction, gravity, collisions, actuation, damping).
    let (a, b) = (trajectory(), trajectory());
    assert!(a.iter().zip(&b).all(|(p, q)| p.x.to_bits() == q.x.to_bits()
        && p.y.to_bits() == q.y.to_bits()
        && p.z.to_bits() == q.z.to_bits()));
}
