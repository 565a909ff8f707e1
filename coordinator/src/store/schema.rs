//! The store's tables (the module documentation of `store` says what each holds).

pub(super) const SCHEMA: &str = "
CREATE TABLE run (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE evaluation (
    task_id INTEGER PRIMARY KEY,
    epoch INTEGER NOT NULL,
    island INTEGER NOT NULL,
    purpose TEXT NOT NULL,
    resolution TEXT NOT NULL,
    genome TEXT NOT NULL,
    outcome TEXT NOT NULL,
    fitness REAL,
    worker TEXT NOT NULL,
    wall_seconds REAL NOT NULL,
    finished_unix REAL NOT NULL
);
CREATE TABLE epoch (
    epoch INTEGER PRIMARY KEY,
    evaluations INTEGER NOT NULL,
    wall_seconds REAL NOT NULL,
    resolution TEXT NOT NULL,
    best_fitness REAL
);
CREATE TABLE population (
    epoch INTEGER NOT NULL,
    island INTEGER NOT NULL,
    slot INTEGER NOT NULL,
    task_id INTEGER NOT NULL,
    fitness REAL,
    PRIMARY KEY (epoch, island, slot)
);
CREATE TABLE migration (
    epoch INTEGER NOT NULL,
    from_island INTEGER NOT NULL,
    to_island INTEGER NOT NULL,
    emigrant_slot INTEGER NOT NULL,
    replaced_slot INTEGER,
    task_id INTEGER NOT NULL
);
CREATE INDEX migration_epoch ON migration(epoch);
CREATE TABLE task_error (task_id INTEGER NOT NULL, worker TEXT NOT NULL, message TEXT NOT NULL);
";

/// Tables added since the first format, created on open, so an older store gains them empty.
pub(super) const ADDED_SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS unchecked (task_id INTEGER PRIMARY KEY);
CREATE TABLE IF NOT EXISTS verification (
    task_id INTEGER NOT NULL,
    claimant TEXT NOT NULL,
    checker TEXT NOT NULL,
    agreed INTEGER NOT NULL,
    claimed TEXT NOT NULL,
    finished_unix REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS quarantine (worker TEXT NOT NULL, task_id INTEGER NOT NULL, finished_unix REAL NOT NULL);
-- When and by whom each evaluation finished, apart from its large genome and outcome: a watcher
-- counts evaluations, measures rates and sums them per worker from this index alone.
CREATE INDEX IF NOT EXISTS evaluation_finished ON evaluation(finished_unix, worker);
CREATE TABLE IF NOT EXISTS history (
    epoch INTEGER NOT NULL,
    island INTEGER NOT NULL,
    best_fitness REAL,
    best_figure REAL,
    mean_fitness REAL,
    replacements INTEGER NOT NULL,
    hypervolume REAL,
    PRIMARY KEY (epoch, island)
);
";
