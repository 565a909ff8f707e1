//! The Rust side of `python/benches/overhead.py`: seconds per `Scene::evaluate` of a saved genome
//! in the quickstart's scene, called in a loop as Python's `Scene.evaluate` is.
//!
//! `cargo bench -p amorph-python --bench evaluate_call -- GENOME RESOLUTION CALLS`

use std::path::Path;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let [genome, resolution, calls] = &args[..] else {
        return Err("usage: evaluate_call GENOME RESOLUTION CALLS".into());
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = amorph_worker::read_scene(&root.join("configs/quickstart.toml"))?;
    let genome = amorph_worker::read_genome(Path::new(genome))?;
    let dims = amorph_worker::parse_resolution(resolution)?;
    let calls: u32 = calls.parse()?;
    std::hint::black_box(scene.evaluate(&genome, dims));
    let start = Instant::now();
    for _ in 0..calls {
        std::hint::black_box(scene.evaluate(std::hint::black_box(&genome), dims));
    }
    println!("{}", start.elapsed().as_secs_f64() / f64::from(calls));
    Ok(())
}
