//! The coordinator's command line and the config reference's agreement with the config structs.

mod cli;
mod config_reference;
