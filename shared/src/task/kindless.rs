//! A scene's table read as its task's scene type, its `kind` key skipped
//! ([`super::Scene::deserialize_kind`]).
//!
//! Why: serde reads an internally tagged enum ([`super::Scene`], tagged by `kind`) by buffering the
//! whole table before it knows the variant, and the buffer forgets where each key stood. A bad value
//! deep inside a scene (`[scene.dynamics] link_precision = "single"`) is then reported at the
//! `[scene]` table. Read through [`Kindless`], the scene type meets the format's own deserializers
//! key by key, and a format that tracks positions (TOML) reports the key's line.

use std::fmt;

use serde::Deserialize;
use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, IntoDeserializer, MapAccess, Visitor};

/// Reads a map as the wrapped deserializer does, without its `kind` entry.
pub(super) struct Kindless<D>(pub(super) D);

impl<'de, D: Deserializer<'de>> Deserializer<'de> for Kindless<D> {
    type Error = D::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_map(SkipKind(visitor))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option
        unit unit_struct newtype_struct seq tuple tuple_struct map struct enum identifier
        ignored_any
    }
}

/// The scene type's visitor, handed the map without `kind`.
struct SkipKind<V>(V);

impl<'de, V: Visitor<'de>> Visitor<'de> for SkipKind<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        self.0.expecting(f)
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.0.visit_map(WithoutKind(map))
    }
}

/// A map's entries but `kind`; each value is still read by the format's own deserializer.
struct WithoutKind<A>(A);

impl<'de, A: MapAccess<'de>> MapAccess<'de> for WithoutKind<A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        let mut seed = Some(seed);
        // The key goes to the scene type inside the format's own key reading, so that an unknown
        // field is reported at the key and not at the table.
        while let Some(key) = self.0.next_key_seed(KeyOrKind(&mut seed))? {
            match key {
                Some(key) => return Ok(Some(key)),
                None => self.0.next_value::<IgnoredAny>().map(drop)?,
            }
        }
        Ok(None)
    }

    fn next_value_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<S::Value, A::Error> {
        self.0.next_value_seed(seed)
    }
}

/// Reads a key: `None` for `kind`, else what the scene type's key seed makes of it (taken once).
struct KeyOrKind<'s, K>(&'s mut Option<K>);

impl<'de, K: DeserializeSeed<'de>> DeserializeSeed<'de> for KeyOrKind<'_, K> {
    type Value = Option<K::Value>;

    fn deserialize<D: Deserializer<'de>>(self, key: D) -> Result<Self::Value, D::Error> {
        let key = String::deserialize(key)?;
        if key == "kind" {
            return Ok(None);
        }
        let seed = self.0.take().expect("a key seed is taken by one key");
        seed.deserialize(key.into_deserializer()).map(Some)
    }
}
