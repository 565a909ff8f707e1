//! What the design benches (`nudge`, `climb`) start from: their arguments, and a design file with
//! the config whose scene judges it.

use amorph::genome::Genome;
use amorph::voxel::GridDims;
use amorph_coordinator::RunConfig;

/// The bench's arguments (without cargo's `--bench`), or its usage line and exit 2 when there are
/// fewer than `least`.
pub fn arguments(least: usize, usage: &str) -> Vec<String> {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.len() < least {
        eprintln!("usage: {usage}");
        std::process::exit(2);
    }
    args
}

/// The genome and resolution of `design` (a `best_genome.json` or a test fixture) and the config
/// at `config`.
pub fn load(design: &str, config: &str) -> (Genome, GridDims, RunConfig) {
    let design: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(design).expect("design file"))
            .expect("design JSON");
    let genome: Genome = serde_json::from_value(design["genome"].clone()).expect("a genome");
    let r: Vec<usize> = serde_json::from_value(design["resolution"].clone()).expect("a resolution");
    let config = RunConfig::load(std::path::Path::new(config)).expect("config");
    (genome, GridDims::new(r[0], r[1], r[2]), config)
}
