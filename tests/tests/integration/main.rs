//! End-to-end tests as one binary (one link instead of one per file): whole runs in one process
//! and across coordinator and worker processes, the cluster under faults and hostile peers, the
//! dashboard, and every command the docs show.

mod beam_run;
mod cluster_determinism;
mod cluster_faults;
mod cluster_hostile_peers;
mod cluster_worker_identity;
mod dashboard;
mod designer_goals;
mod doc_commands;
mod exports_of_a_run;
mod locomotion_run;
mod paper_preset;
mod report_check;
mod search_finest_checks;
mod search_finest_fraction;
mod search_operators;
mod search_pareto;
mod search_skip_unchanged;
mod user_docs_shape;
