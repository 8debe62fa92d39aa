//! Deserialises `[cycle]` without `#[serde(flatten)]` (which would lose toml's line
//! numbers and switch off `deny_unknown_fields`): a map access that hands the three file
//! keys to the shell and every other key, with its span, to the core's derived impl.

use std::path::PathBuf;

use serde::de::value::MapAccessDeserializer;
use serde::de::{DeserializeSeed, Deserializer, IntoDeserializer, MapAccess, Visitor};
use serde::Deserialize;

use super::CycleSection;

/// A key of `[cycle]`: one of the core's fields, or a file key (with the unused seed).
enum Key<F, K> {
    Field(F),
    File(usize, K),
}

const FILE_KEYS: [&str; 3] = ["lut", "reference", "secoc_keys"];

struct KeySeed<K>(K);

impl<'de, K: DeserializeSeed<'de>> DeserializeSeed<'de> for KeySeed<K> {
    type Value = Key<K::Value, K>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        let key = String::deserialize(d)?;
        match FILE_KEYS.iter().position(|k| *k == key) {
            Some(i) => Ok(Key::File(i, self.0)),
            // Inside toml's key deserialisation: an unknown key gets the key's span. The
            // core's "expected one of" list does not know the file keys: they are added.
            None => self
                .0
                .deserialize(key.as_str().into_deserializer())
                .map(Key::Field)
                .map_err(|e: D::Error| {
                    serde::de::Error::custom(format_args!(
                        "{e}, or one of the file keys `lut`, `reference`, `secoc_keys`"
                    ))
                }),
        }
    }
}

struct Split<'f, A> {
    inner: A,
    files: &'f mut [Option<PathBuf>; 3],
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for Split<'_, A> {
    type Error = A::Error;
    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        let mut seed = seed;
        loop {
            match self.inner.next_key_seed(KeySeed(seed))? {
                None => return Ok(None),
                Some(Key::Field(f)) => return Ok(Some(f)),
                Some(Key::File(i, s)) => {
                    let path: PathBuf = self.inner.next_value()?;
                    if let Some(slot) = self.files.get_mut(i) {
                        *slot = Some(path);
                    }
                    seed = s;
                }
            }
        }
    }
    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.inner.next_value_seed(seed)
    }
}

struct SectionVisitor;

impl<'de> Visitor<'de> for SectionVisitor {
    type Value = CycleSection;
    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the [cycle] table")
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<CycleSection, A::Error> {
        let mut files = [None, None, None];
        let decision = restraint::CycleConfig::deserialize(MapAccessDeserializer::new(Split {
            inner: map,
            files: &mut files,
        }))?;
        let [lut, reference, secoc_keys] = files;
        let d = CycleSection::default();
        Ok(CycleSection {
            lut: lut.unwrap_or(d.lut),
            reference: reference.unwrap_or(d.reference),
            secoc_keys: secoc_keys.unwrap_or(d.secoc_keys),
            decision,
        })
    }
}

impl<'de> Deserialize<'de> for CycleSection {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(SectionVisitor)
    }
}
