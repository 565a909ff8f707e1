//! What the design benches (`nudge`, `climb`, `model_sequence`) start from: their arguments, and
//! a design file with the config whose scene judges it.

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

/// The genome and resolution of `design` and the config at `config`, or one line naming the file
/// and exit 2. A test fixture names its resolution; a run's `best_genome.json` does not, and is
/// taken at the config's finest level (where a run that got there keeps its best).
pub fn load(design: &str, config_path: &str) -> (Genome, GridDims, RunConfig) {
    let fail = |what: String| -> ! {
        eprintln!("{what}");
        std::process::exit(2);
    };
    let config = RunConfig::load(std::path::Path::new(config_path))
        .unwrap_or_else(|e| fail(format!("{config_path}: {e}")));
    let text = std::fs::read_to_string(design).unwrap_or_else(|e| fail(format!("{design}: {e}")));
    let file: serde_json::Value =
        serde_json::from_str(&text).unwrap_or_else(|e| fail(format!("{design}: {e}")));
    let genome: Genome = serde_json::from_value(file["genome"].clone())
        .unwrap_or_else(|e| fail(format!("{design}: genome: {e}")));
    let [nx, ny, nz] = match file.get("resolution") {
        Some(r) => serde_json::from_value(r.clone())
            .unwrap_or_else(|e| fail(format!("{design}: resolution: {e}"))),
        None => {
            let finest = *(config.raw.resolution.levels.last())
                .unwrap_or_else(|| fail(format!("{config_path}: no resolution level")));
            eprintln!(
                "{design} names no resolution: taken at the config's finest level {finest:?}"
            );
            finest
        }
    };
    (genome, GridDims::new(nx, ny, nz), config)
}
