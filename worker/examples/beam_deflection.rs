//! A beam design's static deflection as our solver gives it, in the figures a dynamic reader of
//! the exported VXA can report (docs/how-to/voxelyze.md): the tip layer's mean deflection and the
//! displacement of the centre of mass, which is all the VoxCAD-era Voxelyze writes about
//! positions.
//!
//! `cargo run --release -p amorph-worker --example beam_deflection -- <genome.json> <scene.toml> <NXxNYxNZ>`

use amorph::task::cantilever::solve_cantilever;
use amorph::task::{Scene, Task};
use anyhow::{Context, bail};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [genome, scene, resolution] = args.as_slice() else {
        bail!("usage: beam_deflection <genome.json> <scene.toml> <NXxNYxNZ>");
    };
    let genome = amorph_worker::read_genome(genome.as_ref())?;
    let Scene::Beam(beam) = amorph_worker::read_scene(scene.as_ref())? else {
        bail!("{scene}: not a beam scene");
    };
    let dims = amorph_worker::parse_resolution(resolution)?;
    let grid = amorph::task::design(&beam, &genome, dims);
    let voxel_size = beam.length / dims.ny as f64;
    let solved = solve_cantilever(
        &grid,
        &beam.palette,
        voxel_size,
        beam.tip_load,
        &beam.solver,
    )
    .map_err(|f| anyhow::anyhow!("{f:?}"))
    .context("solving the cantilever")?;
    let (mut mass, mut moment) = (0.0, [0.0; 3]);
    for (cell, material) in grid.cells().iter().enumerate() {
        let Some(material) = material else {
            continue;
        };
        let m = beam.palette.0[material.index()].density * voxel_size.powi(3);
        let u = solved.displacement(cell);
        mass += m;
        for (sum, u) in moment.iter_mut().zip(u) {
            *sum += m * u;
        }
    }
    let centre = moment.map(|s| s / mass);
    let outcome = beam.simulate(&grid);
    let tip = outcome.metrics().map_or(f64::NAN, |m| m.tip_deflection);
    println!("voxels {}", grid.filled_count());
    println!("tip_deflection_m {tip:e}");
    println!(
        "centre_of_mass_displacement_m {:e} {:e} {:e}",
        centre[0], centre[1], centre[2]
    );
    Ok(())
}
