//! Scenes read from TOML text, with a bad key reported at its own line.
//!
//! A scene arrives as the `[scene]` table of a run config (the coordinator) or as a file holding
//! a config or a bare scene table (`worker evaluate`). Read as [`Scene`], an error inside the
//! scene is placed at the `[scene]` header, because serde buffers a tagged table before it knows
//! the variant ([`kindless`](super::kindless)). [`relocate`] reads the scene again as the type
//! its `kind` names, which meets TOML's own reader key by key, and returns the same error at the
//! key's place; [`locate`] turns an error into the line a person fixes.

use std::fmt;

use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, Visitor};

use super::Scene;

/// Where the scene stands in the text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneAt {
    /// The `[scene]` table of a run config.
    Config,
    /// The whole document is the scene table.
    Document,
}

/// `original`'s error found again at its key, by reading the scene as the type its `kind` names;
/// `None` where that reading succeeds, finds another error (the message must be the same, so a
/// relocated error is never a different complaint), or the scene has no `kind` to read by.
pub fn relocate(text: &str, at: SceneAt, original: &toml::de::Error) -> Option<toml::de::Error> {
    let document: toml::Table = text.parse().ok()?;
    let table = match at {
        SceneAt::Config => document.get("scene")?.as_table()?,
        SceneAt::Document => &document,
    };
    let kind = table.get("kind")?.as_str()?;
    let parsed = toml::Deserializer::parse(text).ok()?;
    let error = match at {
        SceneAt::Config => ConfigScene(kind).deserialize(parsed).err()?,
        SceneAt::Document => SceneOfKind(kind).deserialize(parsed).err()?,
    };
    (error.span().is_some() && error.message() == original.message()).then_some(error)
}

/// An error placed in `text`: its line (1-based), and the message with that line's text
/// quoted in front (cut to 80 characters), which names the key or table it is about.
pub fn locate(text: &str, error: &toml::de::Error) -> (usize, String) {
    let start = error.span().map_or(0, |s| s.start.min(text.len()));
    let line = text[..start].matches('\n').count() + 1;
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let quoted: String = text[line_start..]
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .chars()
        .take(80)
        .collect();
    let message = error.message().replace('\n', " ");
    if quoted.is_empty() {
        (line, message)
    } else {
        (line, format!("`{quoted}`: {message}"))
    }
}

/// A scene from TOML text, its errors as `line N: ...` (see [`locate`]).
pub fn scene_from_toml(text: &str, at: SceneAt) -> Result<Scene, String> {
    #[derive(serde::Deserialize)]
    struct WithScene {
        scene: Scene,
    }
    let read = match at {
        SceneAt::Config => toml::from_str::<WithScene>(text).map(|w| w.scene),
        SceneAt::Document => toml::from_str::<Scene>(text),
    };
    read.map_err(|e| {
        let e = relocate(text, at, &e).unwrap_or(e);
        let (line, message) = locate(text, &e);
        format!("line {line}: {message}")
    })
}

/// A run config's `scene` entry read with [`Scene::deserialize_kind`] as the scene of this kind,
/// every other entry skipped.
struct ConfigScene<'k>(&'k str);

impl<'de> DeserializeSeed<'de> for ConfigScene<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, document: D) -> Result<(), D::Error> {
        document.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for ConfigScene<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a run config")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        while let Some(key) = map.next_key::<String>()? {
            if key == "scene" {
                map.next_value_seed(SceneOfKind(self.0))?;
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(())
    }
}

/// A table read as the scene of one kind.
struct SceneOfKind<'k>(&'k str);

impl<'de> DeserializeSeed<'de> for SceneOfKind<'_> {
    type Value = Scene;

    fn deserialize<D: Deserializer<'de>>(self, table: D) -> Result<Scene, D::Error> {
        Scene::deserialize_kind(self.0, table)
    }
}

#[cfg(test)]
mod tests;
