//! Command-line overrides, `--set key=value`: a dotted key path into the config document and a
//! TOML value, applied to the document before its preset, so they are validated like the file's
//! own keys and recorded in the run's `config.toml`.

use std::str::FromStr;

/// One `--set key=value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The dotted key path, e.g. `search.local_search.fraction`.
    pub path: Vec<String>,
    pub value: toml::Value,
    /// As the user wrote it, for messages.
    pub text: String,
}

impl FromStr for Override {
    type Err = String;

    /// `key=value`: the value is read as TOML (`0.5`, `true`, `[6000]`, `"ring"`), and a bare
    /// word that is not TOML (`polynomial4`) as a string.
    fn from_str(text: &str) -> Result<Self, String> {
        let (key, value) = text
            .split_once('=')
            .ok_or_else(|| format!("--set {text}: expected key=value"))?;
        let path: Vec<String> = key.trim().split('.').map(str::to_owned).collect();
        if path.iter().any(|p| p.is_empty()) {
            return Err(format!("--set {text}: the key {key:?} has an empty part"));
        }
        let value = value.trim();
        let value = match format!("v = {value}").parse::<toml::Table>() {
            Ok(mut table) => table.remove("v").expect("the key just written"),
            Err(_) => toml::Value::String(value.to_owned()),
        };
        Ok(Self {
            path,
            value,
            text: text.to_owned(),
        })
    }
}

impl Override {
    /// Sets the value in `document`, creating the tables on its path; fails where the path runs
    /// through a key that is not a table.
    pub fn apply(&self, document: &mut toml::Table) -> Result<(), String> {
        let (last, tables) = self.path.split_last().expect("a path has a key");
        let mut table = document;
        for (depth, key) in tables.iter().enumerate() {
            let entry = table
                .entry(key.clone())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            table = entry.as_table_mut().ok_or_else(|| {
                format!(
                    "--set {}: {} is not a table",
                    self.text,
                    self.path[..=depth].join(".")
                )
            })?;
        }
        table.insert(last.clone(), self.value.clone());
        Ok(())
    }
}

#[cfg(test)]
mod tests;
