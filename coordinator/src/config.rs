//! The run configuration: a TOML file read strictly (unknown keys are errors) and validated into a
//! [`RunConfig`] before anything runs. Every error is one line naming the key.

use std::path::{Path, PathBuf};

use amorph::genome::MutationParams;
use amorph::scene::Scene;
use serde::{Deserialize, Serialize};

use crate::search::{
    CrossoverParams, LocalSearchParams, MigrationParams, ResolutionSchedule, StepAdaptation,
    Variation,
};

#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read config {path}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("config {path}, line {line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("config {path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, ConfigError>;

/// The file as written: every section and key, with defaults for what may be left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawConfig {
    /// Name of the run; results go to `<results_dir>/<name>/`.
    pub name: String,
    /// The one seed every random choice of the run derives from.
    #[serde(default)]
    pub seed: u64,
    /// Folder that receives one sub-folder per run.
    #[serde(default = "default_results_dir")]
    pub results_dir: PathBuf,
    #[serde(default)]
    pub cluster: ClusterSection,
    #[serde(default)]
    pub search: SearchSection,
    #[serde(default)]
    pub budget: BudgetSection,
    pub resolution: ResolutionSchedule,
    pub scene: Scene,
}

fn default_results_dir() -> PathBuf {
    PathBuf::from("results")
}

/// How the coordinator serves workers. Nothing here changes a run's result, so it may differ
/// when a run is resumed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClusterSection {
    /// Address workers connect to; port 0 picks a free one. 127.0.0.1 keeps the coordinator
    /// private to this machine; use 0.0.0.0:PORT (with a token) for workers on other machines.
    pub listen: String,
    /// Workers started inside the coordinator process, talking to it over loopback gRPC like any
    /// other worker. Unset: one per core. 0: only external `worker --connect` processes.
    pub local_workers: Option<usize>,
    /// Evaluation threads of each local worker.
    pub local_worker_threads: usize,
    /// File holding the shared secret workers must present (surrounding whitespace ignored). The
    /// AMORPH_TOKEN environment variable, if set, takes precedence.
    pub token_file: Option<PathBuf>,
    /// PEM certificate chain and private key: serve TLS (workers connect with https://).
    pub tls_cert: Option<PathBuf>,
    pub tls_key: Option<PathBuf>,
    /// Name in the certificate that local workers check (default "localhost").
    pub tls_domain: Option<String>,
    /// How often workers heartbeat, ms.
    pub heartbeat_ms: u64,
    /// How long a lease lasts without a heartbeat naming its task, ms.
    pub lease_ms: u64,
    /// A worker silent this long is dropped and its leases re-queued, ms.
    pub worker_timeout_ms: u64,
    /// Worker errors after which a task is marked failed instead of retried.
    pub max_attempts: u32,
}

impl Default for ClusterSection {
    fn default() -> Self {
        Self {
            listen: "127.0.0.1:0".into(),
            local_workers: None,
            local_worker_threads: 1,
            token_file: None,
            tls_cert: None,
            tls_key: None,
            tls_domain: None,
            heartbeat_ms: 1000,
            lease_ms: 10_000,
            worker_timeout_ms: 5000,
            max_attempts: 3,
        }
    }
}

impl ClusterSection {
    /// Local workers to start: the configured count, or one per core.
    pub fn local_worker_count(&self) -> usize {
        self.local_workers
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    pub fn queue_rules(&self) -> crate::cluster::QueueRules {
        use std::time::Duration;
        crate::cluster::QueueRules {
            lease: Duration::from_millis(self.lease_ms),
            heartbeat_interval: Duration::from_millis(self.heartbeat_ms),
            worker_timeout: Duration::from_millis(self.worker_timeout_ms),
            max_attempts: self.max_attempts,
        }
    }

    /// The shared secret: AMORPH_TOKEN, else the token file, else none.
    pub fn token(&self) -> std::result::Result<Option<String>, String> {
        if let Ok(token) = std::env::var("AMORPH_TOKEN")
            && !token.trim().is_empty()
        {
            return Ok(Some(token.trim().to_owned()));
        }
        match &self.token_file {
            None => Ok(None),
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .map_err(|e| format!("cluster.token_file {}: {e}", path.display()))?;
                let token = text.trim();
                if token.is_empty() {
                    return Err(format!("cluster.token_file {} is empty", path.display()));
                }
                Ok(Some(token.to_owned()))
            }
        }
    }

    fn validate(&self) -> std::result::Result<(), String> {
        if self.listen.parse::<std::net::SocketAddr>().is_err()
            && !self
                .listen
                .rsplit_once(':')
                .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok())
        {
            return Err(format!(
                "cluster.listen = {:?} is not HOST:PORT",
                self.listen
            ));
        }
        if self.local_worker_threads == 0 {
            return Err("cluster.local_worker_threads must be at least 1".into());
        }
        if self.tls_cert.is_some() != self.tls_key.is_some() {
            return Err(
                "cluster.tls_cert and cluster.tls_key go together: set both or neither".into(),
            );
        }
        if self.heartbeat_ms < 10 {
            return Err("cluster.heartbeat_ms must be at least 10".into());
        }
        if self.lease_ms <= self.heartbeat_ms {
            return Err("cluster.lease_ms must be longer than cluster.heartbeat_ms".into());
        }
        if self.worker_timeout_ms <= self.heartbeat_ms {
            return Err(
                "cluster.worker_timeout_ms must be longer than cluster.heartbeat_ms".into(),
            );
        }
        if self.max_attempts == 0 {
            return Err("cluster.max_attempts must be at least 1".into());
        }
        Ok(())
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SearchSection {
    /// Individuals per island (paper: 50).
    pub population: usize,
    /// Number of islands.
    pub islands: usize,
    /// Children each island breeds per epoch (evaluated in parallel).
    pub children_per_epoch: usize,
    /// Gaussian points in each initial random genome.
    pub initial_points: usize,
    pub mutation: MutationParams,
    pub migration: MigrationParams,
    /// Nudges of each island's best design (off by default).
    pub local_search: LocalSearchParams,
    /// Adapting the mutation step to each island's success (fixed by default).
    pub step_adaptation: StepAdaptation,
    /// Where crossover cuts (uniformly oriented planes by default, as in the paper).
    pub crossover: CrossoverParams,
}

impl SearchSection {
    /// The variation policies beyond the paper's operators.
    pub fn variation(&self) -> Variation {
        Variation {
            local_search: self.local_search.clone(),
            step_adaptation: self.step_adaptation.clone(),
            crossover: self.crossover.clone(),
        }
    }
}

impl Default for SearchSection {
    fn default() -> Self {
        Self {
            population: 50,
            islands: 1,
            children_per_epoch: 50,
            initial_points: 40,
            mutation: MutationParams::default(),
            migration: MigrationParams::default(),
            local_search: LocalSearchParams::default(),
            step_adaptation: StepAdaptation::default(),
            crossover: CrossoverParams::default(),
        }
    }
}

/// When to stop; the first limit reached ends the run. At least one must be set.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BudgetSection {
    /// Total evaluations, including the initial population and re-evaluations at a new resolution.
    pub evaluations: Option<u64>,
    /// Wall-clock seconds (the one limit that depends on machine speed).
    pub wall_seconds: Option<f64>,
    /// Stop once the best design's RMS error (beam task, finest resolution) is at most this, %.
    pub target_rms_percent: Option<f64>,
}

/// A validated configuration: what [`crate::run`] accepts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunConfig {
    pub raw: RawConfig,
    /// Where this config came from, for messages.
    pub source: PathBuf,
}

impl RunConfig {
    /// Reads, parses and validates a config file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates config text; `path` only names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let raw: RawConfig = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| {
                text[..s.start.min(text.len())].matches('\n').count() + 1
            });
            ConfigError::Parse {
                path: path.to_owned(),
                line,
                message: e.message().replace('\n', " "),
            }
        })?;
        Self::try_from_raw(raw, path)
    }

    pub fn try_from_raw(raw: RawConfig, path: &Path) -> Result<Self> {
        validate(&raw).map_err(|message| ConfigError::Invalid {
            path: path.to_owned(),
            message,
        })?;
        Ok(Self {
            raw,
            source: path.to_owned(),
        })
    }

    /// The folder this run writes its results into.
    pub fn run_dir(&self) -> PathBuf {
        self.raw.results_dir.join(&self.raw.name)
    }
}

fn validate(raw: &RawConfig) -> std::result::Result<(), String> {
    let s = &raw.search;
    if raw.name.is_empty() || raw.name.contains(['/', '\\']) || raw.name.starts_with('.') {
        return Err(format!("name = {:?} must be a plain folder name", raw.name));
    }
    if s.population < 2 {
        return Err("search.population must be at least 2".into());
    }
    if s.islands == 0 {
        return Err("search.islands must be at least 1".into());
    }
    if s.children_per_epoch == 0 {
        return Err("search.children_per_epoch must be at least 1".into());
    }
    let limits = raw.scene.limits();
    if s.initial_points == 0 || s.initial_points > limits.max_points {
        return Err(format!(
            "search.initial_points must be between 1 and scene.limits.max_points ({})",
            limits.max_points
        ));
    }
    s.mutation
        .validate()
        .map_err(|field| format!("search.mutation.{field} is out of range"))?;
    if let crate::search::Topology::Random { probability } = s.migration.topology
        && !(0.0..=1.0).contains(&probability)
    {
        return Err("search.migration.topology.probability must be in [0, 1]".into());
    }
    s.variation().validate()?;
    let b = &raw.budget;
    if b.evaluations.is_none() && b.wall_seconds.is_none() && b.target_rms_percent.is_none() {
        return Err(
            "budget: set at least one of evaluations, wall_seconds, target_rms_percent".into(),
        );
    }
    let initial = (s.islands * s.population) as u64;
    if let Some(n) = b.evaluations
        && n < initial
    {
        return Err(format!(
            "budget.evaluations = {n} does not cover the initial populations ({} islands x {} individuals)",
            s.islands, s.population
        ));
    }
    if let Some(w) = b.wall_seconds
        && !(w.is_finite() && w > 0.0)
    {
        return Err("budget.wall_seconds must be a positive number".into());
    }
    if let Some(t) = b.target_rms_percent
        && !(t.is_finite() && t >= 0.0)
    {
        return Err("budget.target_rms_percent must be a non-negative number".into());
    }
    if b.target_rms_percent.is_some() && !matches!(raw.scene, amorph::scene::Scene::Beam(_)) {
        return Err("budget.target_rms_percent applies to beam scenes only".into());
    }
    raw.cluster.validate()?;
    raw.resolution.validate()?;
    if matches!(raw.scene, amorph::scene::Scene::Beam(_)) {
        // The beam runs along y (clamped at y = 0, loaded at the last y layer, deflecting in −z):
        // [12, 12, 40] would be a 12-voxel-long beam 40 voxels deep, almost surely a slip for the
        // paper's [12, 40, 12].
        for (i, &[nx, ny, nz]) in raw.resolution.levels.iter().enumerate() {
            if ny < nx || ny < nz {
                return Err(format!(
                    "resolution.levels[{i}] = [{nx}, {ny}, {nz}]: a beam runs along y, so ny must be its longest count (did you mean [{nx}, {nz}, {ny}]?)"
                ));
            }
        }
    }
    raw.scene.validate().map_err(|e| format!("scene: {e}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
name = "t"
[budget]
evaluations = 100
[resolution]
levels = [[6, 20, 6]]
[scene]
kind = "beam"
target = "straight"
"#;

    #[test]
    fn a_minimal_config_is_accepted_with_paper_defaults() {
        let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
        assert_eq!(c.raw.search.population, 50);
        assert_eq!(c.raw.search.mutation.probability, 0.2);
    }

    #[test]
    fn an_unknown_key_is_one_line_naming_it() {
        let text = MINIMAL.replace("[budget]", "[budget]\nevaluation = 3");
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("evaluation") && err.contains("line 4"),
            "{err}"
        );
        assert!(!err.contains('\n'), "{err}");
    }

    #[test]
    fn an_invalid_value_names_the_key() {
        let text = MINIMAL.replace("evaluations = 100", "evaluations = 10");
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("budget.evaluations"), "{err}");
    }

    #[test]
    fn an_unknown_target_is_named() {
        let text = MINIMAL.replace("\"straight\"", "\"wavy\"");
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("wavy"), "{err}");
    }

    #[test]
    fn the_search_variation_keys_default_off_and_a_bad_one_is_named() {
        let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
        assert_eq!(
            c.raw.search.variation(),
            crate::search::Variation::default()
        );
        assert_eq!(c.raw.search.local_search.fraction, 0.0);
        assert!(c.raw.search.migration.only_if_fitter);
        let text = MINIMAL.replace(
            "[budget]",
            "[search.local_search]\nfraction = 2.0\n[budget]",
        );
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("search.local_search.fraction"), "{err}");
    }
}
