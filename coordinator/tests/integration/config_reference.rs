//! The key reference (docs/reference/config.md) against the config structs, so that neither can
//! drift: every key a run writes into its config.toml is documented, every documented key is one
//! the parser knows, and every default the reference gives as a value is the value a config that
//! leaves the key out gets.

use std::collections::BTreeSet;
use std::path::Path;

use amorph_coordinator::RunConfig;
use amorph_coordinator::config::Override;

const KINDS: [&str; 3] = ["beam", "locomotion", "stiffness"];

/// One documented key: the scene kind its section is for (`None`: every kind), its dotted path,
/// and its default when the reference gives it as a TOML value.
#[derive(Debug)]
struct Documented {
    kind: Option<String>,
    path: String,
    default: Option<toml::Value>,
}

fn reference() -> Vec<Documented> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/reference/config.md");
    let text = std::fs::read_to_string(&path).expect("docs/reference/config.md");
    let mut keys = Vec::new();
    let mut section: Option<(Vec<String>, Option<String>)> = None;
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            section = if heading.trim() == "top level" {
                Some((Vec::new(), None))
            } else {
                table_heading(heading)
            };
            continue;
        }
        let Some((prefix, kind)) = &section else {
            continue;
        };
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | `key` | type | unit | default | range | meaning |
        if cells.len() < 8 || !cells[1].starts_with('`') {
            continue;
        }
        let key = cells[1].trim_matches('`');
        let default = (cells[4].starts_with('`') && cells[4].ends_with('`'))
            .then(|| cells[4].trim_matches('`'))
            .and_then(|v| format!("v = {v}").parse::<toml::Table>().ok())
            .and_then(|mut t| t.remove("v"));
        let mut path = prefix.clone();
        path.push(key.to_owned());
        keys.push(Documented {
            kind: kind.clone(),
            path: path.join("."),
            default,
        });
    }
    keys
}

/// "`[scene.dynamics]` (locomotion)" -> (["scene", "dynamics"], Some("locomotion")).
fn table_heading(heading: &str) -> Option<(Vec<String>, Option<String>)> {
    let start = heading.find("`[")? + 2;
    let end = start + heading[start..].find("]`")?;
    let path = heading[start..end].trim_matches(|c| c == '[' || c == ']');
    let kind = KINDS
        .iter()
        .find(|k| heading[end..].contains(&format!("({k})")))
        .map(|k| k.to_string());
    Some((path.split('.').map(str::to_owned).collect(), kind))
}

/// A config of `kind` that names only what it must: every other key takes its default.
fn minimal(kind: &str) -> String {
    let levels = if kind == "locomotion" {
        "[[6, 6, 6]]"
    } else {
        "[[4, 12, 4]]"
    };
    let target = if kind == "beam" {
        "target = \"circular_arc\"\n"
    } else {
        ""
    };
    format!(
        "name = \"reference\"\n[budget]\nevaluations = 1000\n[resolution]\nlevels = {levels}\n\
         [scene]\nkind = \"{kind}\"\n{target}"
    )
}

fn parse(kind: &str, sets: &[String]) -> Result<RunConfig, String> {
    let sets: Vec<Override> = sets.iter().map(|s| s.parse().unwrap()).collect();
    RunConfig::parse_with(&minimal(kind), Path::new("reference.toml"), &sets)
        .map_err(|e| e.to_string())
}

/// Every leaf key of `table` as a dotted path (an array of tables contributes its tables' keys).
fn leaves(table: &toml::Table, prefix: &str, out: &mut Vec<(String, toml::Value)>) {
    for (key, value) in table {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            toml::Value::Table(t) => leaves(t, &path, out),
            toml::Value::Array(a) if !a.is_empty() && a.iter().all(toml::Value::is_table) => {
                for t in a {
                    leaves(t.as_table().expect("checked"), &path, out);
                }
            }
            _ => out.push((path, value.clone())),
        }
    }
}

fn written(kind: &str) -> Vec<(String, toml::Value)> {
    let config = parse(kind, &[]).unwrap();
    let table: toml::Table = toml::to_string(&config.to_raw()).unwrap().parse().unwrap();
    let mut out = Vec::new();
    leaves(&table, "", &mut out);
    out
}

fn documented_for<'a>(keys: &'a [Documented], kind: &str, path: &str) -> Option<&'a Documented> {
    keys.iter()
        .find(|d| d.path == path && d.kind.as_deref().is_none_or(|k| k == kind))
}

#[test]
fn every_written_key_is_documented() {
    let keys = reference();
    assert!(
        keys.len() > 40,
        "only {} keys parsed from the reference",
        keys.len()
    );
    let mut missing = BTreeSet::new();
    for kind in KINDS {
        for (path, _) in written(kind) {
            if documented_for(&keys, kind, &path).is_none() {
                missing.insert(format!("{path} ({kind})"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "keys a run writes but the reference lacks: {missing:?}"
    );
}

/// A datetime is a value no config key takes, so setting a key to one fails for a known key
/// with a type error and for an unknown one with "unknown field" naming it.
#[test]
fn every_documented_key_is_one_the_parser_knows() {
    let mut unknown = Vec::new();
    for d in reference() {
        let kinds: Vec<&str> = match &d.kind {
            Some(k) => vec![k.as_str()],
            None => KINDS.to_vec(),
        };
        let last = d.path.rsplit('.').next().expect("a path has a key");
        let unknown_field = format!("unknown field `{last}`");
        let set = format!("{}=1979-05-27", d.path);
        let known = kinds
            .iter()
            .any(|kind| match parse(kind, std::slice::from_ref(&set)) {
                Ok(_) => true,
                Err(e) => !e.contains(&unknown_field) && !e.contains("is not a table"),
            });
        if !known {
            unknown.push(d.path.clone());
        }
    }
    assert!(
        unknown.is_empty(),
        "documented keys the parser does not know: {unknown:?}"
    );
}

#[test]
fn every_documented_default_is_the_default() {
    let keys = reference();
    let mut wrong = Vec::new();
    for kind in KINDS {
        for (path, value) in written(kind) {
            let Some(d) = documented_for(&keys, kind, &path) else {
                continue;
            };
            let Some(default) = &d.default else {
                continue;
            };
            let same = match (default, &value) {
                (toml::Value::Integer(a), toml::Value::Float(b))
                | (toml::Value::Float(b), toml::Value::Integer(a)) => *a as f64 == *b,
                (a, b) => a == b,
            };
            if !same {
                wrong.push(format!("{path} ({kind}): documented {default}, is {value}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
}
