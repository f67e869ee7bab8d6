//! A strict reader for `[[constraints]]` entries: JSON values without repeated keys or deep
//! nesting.

use serde::Deserialize;
use serde_json::{Map, Value};

/// How deep a constraint entry may nest (`box = { min = [..] }` is 3 levels).
const MAX_ENTRY_DEPTH: usize = 32;

/// A `[[constraints]]` or `[[colliders]]` entry as JSON values, read strictly: a key given
/// twice is refused (serde_json's own map keeps the last one silently) and so is nesting deeper
/// than [`MAX_ENTRY_DEPTH`] (building `serde_json::Value` recurses once per level, and TOML's
/// dotted keys nest without its parser's limit). Any value is read, so that one which is not a
/// table is refused by [`Entry::table`] with its list and index (a JSON `null` in the list).
pub(super) struct Entry(Value);

impl Entry {
    /// The entry's keys.
    ///
    /// # Errors
    /// A message for an entry that is not a table, naming what it is.
    pub(super) fn table(self) -> Result<Map<String, Value>, String> {
        match self.0 {
            Value::Object(map) => Ok(map),
            Value::Null => Err("must be a table, found null".into()),
            Value::Bool(_) => Err("must be a table, found a boolean".into()),
            Value::Number(_) => Err("must be a table, found a number".into()),
            Value::String(_) => Err("must be a table, found a string".into()),
            Value::Array(_) => Err("must be a table, found a list".into()),
        }
    }
}

/// The visitor methods of every value that is not a list or a table, each refused by the
/// visitor's own `refuse(found)` (which names the key: serde's "invalid type: null, expected a
/// sequence" names none).
macro_rules! refuse_plain_values {
    () => {
        fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<Self::Value, E> {
            Err(self.refuse("a boolean"))
        }
        fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<Self::Value, E> {
            Err(self.refuse("a number"))
        }
        fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<Self::Value, E> {
            Err(self.refuse("a number"))
        }
        fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<Self::Value, E> {
            Err(self.refuse("a number"))
        }
        fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<Self::Value, E> {
            Err(self.refuse("a string"))
        }
        fn visit_unit<E: serde::de::Error>(self) -> Result<Self::Value, E> {
            Err(self.refuse("null"))
        }
        fn visit_none<E: serde::de::Error>(self) -> Result<Self::Value, E> {
            Err(self.refuse("null"))
        }
    };
}

/// A top-level list of entries (`constraints`, `colliders`), each read as an [`Entry`]; any
/// other value is refused naming the key and what it is (a JSON `"colliders": null`).
pub(super) struct EntryList(pub(super) &'static str);

impl EntryList {
    fn refuse<E: serde::de::Error>(&self, found: &str) -> E {
        let key = self.0;
        E::custom(format!("`{key}` must be a list of [[{key}]] tables, found {found}"))
    }
}

impl<'de> serde::de::Visitor<'de> for EntryList {
    type Value = Vec<Entry>;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a list of [[{}]] tables", self.0)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<Entry>, A::Error> {
        // Not sized by the hint: it may claim more than the input holds.
        let mut list = Vec::new();
        while let Some(entry) = seq.next_element()? {
            list.push(entry);
        }
        Ok(list)
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, _: A) -> Result<Vec<Entry>, A::Error> {
        Err(self.refuse("a table"))
    }
    refuse_plain_values!();
}

/// A top-level table (`[mesh]`, `[solver]`, `[contact]`, `[output]`) as one table. A derived
/// struct also reads a list positionally, so `output = ["out", "r.json"]` was taken for a path
/// and a report, and `[[contact]]` refused as "expected a boolean" (its first field), instead
/// of by what is wrong; a JSON `"contact": null` is refused naming the key.
pub(super) struct OneTable<T>(pub(super) &'static str, pub(super) std::marker::PhantomData<T>);

impl<T> OneTable<T> {
    fn refuse<E: serde::de::Error>(&self, found: &str) -> E {
        let key = self.0;
        E::custom(format!("`{key}` must be one [{key}] table, found {found}"))
    }
}

impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for OneTable<T> {
    type Value = T;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "one [{}] table", self.0)
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, _: A) -> Result<Self::Value, A::Error> {
        let key = self.0;
        Err(serde::de::Error::custom(format!("`{key}` must be one [{key}] table (not a list: [[{key}]] or [...])")))
    }
    refuse_plain_values!();
}

impl<'de> Deserialize<'de> for Entry {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(StrictValue { depth: 0 }).map(Entry)
    }
}

/// Builds a `serde_json::Value` refusing repeated keys and deep nesting.
#[derive(Clone, Copy)]
pub(super) struct StrictValue {
    depth: usize,
}

impl StrictValue {
    /// A whole JSON text as a tree, read strictly (the nesting counted from its top).
    pub(super) fn read_json(text: &str) -> Result<Value, serde_json::Error> {
        use serde::de::DeserializeSeed;
        let mut deserializer = serde_json::Deserializer::from_str(text);
        let value = StrictValue { depth: 0 }.deserialize(&mut deserializer)?;
        deserializer.end()?;
        Ok(value)
    }

    /// A whole TOML text as a tree, read strictly: its inf and nan refused at their line
    /// (`toml::from_str` into a `Value` makes them null).
    pub(super) fn read_toml(text: &str) -> Result<Value, toml::de::Error> {
        use serde::de::DeserializeSeed;
        StrictValue { depth: 0 }.deserialize(toml::de::Deserializer::parse(text)?)
    }

    fn deeper<E: serde::de::Error>(self) -> Result<StrictValue, E> {
        if self.depth >= MAX_ENTRY_DEPTH {
            return Err(E::custom(format!("nested deeper than {MAX_ENTRY_DEPTH} levels")));
        }
        Ok(StrictValue { depth: self.depth + 1 })
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for StrictValue {
    type Value = Value;
    fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Value, D::Error> {
        deserializer.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for StrictValue {
    type Value = Value;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Value, E> {
        // TOML's inf and nan: JSON has no such numbers (serde_json would make them null, and a
        // builder would then say "found null" of a value the file spells nan).
        serde_json::Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| E::custom(format!("numbers must be finite, found {}", spelled(v))))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_owned()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_some<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Value, D::Error> {
        deserializer.deserialize_any(self)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let inner = self.deeper()?;
        // Not sized by the hint: it may claim more than the input holds.
        let mut list = Vec::new();
        while let Some(v) = seq.next_element_seed(inner)? {
            list.push(v);
        }
        Ok(Value::Array(list))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let inner = self.deeper()?;
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(serde::de::Error::custom(format!("duplicate key `{key}`")));
            }
            let value = map.next_value_seed(inner)?;
            out.insert(key, value);
        }
        Ok(Value::Object(out))
    }
}

/// A number as TOML spells it (`nan`, `inf`, `-inf`; Rust prints `NaN`), for messages.
pub(super) fn spelled(v: f64) -> String {
    if v.is_nan() { "nan".into() } else { v.to_string() }
}
