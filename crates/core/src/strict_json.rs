//! JSON as the server reads it from clients: like [`serde_json::from_str`], but an
//! object that names a key twice is refused instead of its last value silently winning.
//! Two readers of the same document (a proxy, a logger, a replay verifier) could
//! otherwise act on different values of the same field.

use serde::de::{Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};
use std::fmt;

/// Why a document was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refused {
    /// Not JSON at all: serde_json's message, with line and column.
    Malformed(String),
    /// JSON, but an object names a key twice: `path` is the object's place in the
    /// document (`agents[1]`), empty for the top level; `message` names the key
    /// (`duplicate key "id" at line 1 column 30`).
    DuplicateKey {
        /// Where the object is, as a path into the document (`agents[1]`).
        path: String,
        /// Which key, and where in the text.
        message: String,
    },
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refused::Malformed(message) => f.write_str(message),
            Refused::DuplicateKey { path, message } if path.is_empty() => f.write_str(message),
            Refused::DuplicateKey { path, message } => write!(f, "{path}: {message}"),
        }
    }
}

/// Parses `text` as one JSON document whose objects have no key twice.
pub fn parse(text: &[u8]) -> Result<Value, Refused> {
    let mut de = serde_json::Deserializer::from_slice(text);
    let value: Unique = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        let error = e.into_inner();
        // The only data error this reader raises is a repeated key (`visit_map`);
        // every other error is the text's.
        match error.classify() {
            serde_json::error::Category::Data => Refused::DuplicateKey {
                path: if path == "." { String::new() } else { path },
                message: error.to_string(),
            },
            _ => Refused::Malformed(error.to_string()),
        }
    })?;
    de.end().map_err(|e| Refused::Malformed(e.to_string()))?;
    Ok(value.0)
}

/// A JSON value read with a check for repeated keys at every depth.
struct Unique(Value);

impl<'de> Deserialize<'de> for Unique {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueVisitor).map(Unique)
    }
}

struct UniqueVisitor;

impl<'de> Visitor<'de> for UniqueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, b: bool) -> Result<Value, E> {
        Ok(Value::Bool(b))
    }
    fn visit_i64<E>(self, n: i64) -> Result<Value, E> {
        Ok(Value::from(n))
    }
    fn visit_u64<E>(self, n: u64) -> Result<Value, E> {
        Ok(Value::from(n))
    }
    fn visit_f64<E>(self, n: f64) -> Result<Value, E> {
        Ok(Value::from(n))
    }
    fn visit_str<E>(self, s: &str) -> Result<Value, E> {
        Ok(Value::String(s.to_owned()))
    }
    fn visit_string<E>(self, s: String) -> Result<Value, E> {
        Ok(Value::String(s))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        while let Some(Unique(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(Value::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut object = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(serde::de::Error::custom(format!("duplicate key \"{key}\"")));
            }
            let Unique(value) = map.next_value()?;
            object.insert(key, value);
        }
        Ok(Value::Object(object))
    }
}

#[cfg(test)]
mod tests {
    use super::{parse, Refused};
    use serde_json::json;

    #[test]
    fn documents_without_repeated_keys_read_as_serde_json_reads_them() {
        let text = r#"{"a": [1, -2, 3.5, "x", null, true, {"b": {}}], "c": {"a": 1}}"#;
        assert_eq!(
            parse(text.as_bytes()).unwrap(),
            serde_json::from_str::<serde_json::Value>(text).unwrap()
        );
        assert_eq!(parse(b"7").unwrap(), json!(7));
    }

    #[test]
    fn a_repeated_key_is_refused_at_any_depth_and_named_with_its_path() {
        let refused = |text: &str| match parse(text.as_bytes()) {
            Err(e @ Refused::DuplicateKey { .. }) => e.to_string(),
            other => panic!("{text}: {other:?}"),
        };
        let top = refused(r#"{"tick": 1, "tick": 2}"#);
        assert!(top.starts_with("duplicate key \"tick\" at line 1"), "{top}");
        let deep = refused(r#"{"agents": [{"id": "a"}, {"id": "b", "id": "c"}]}"#);
        assert!(
            deep.starts_with("agents[1]: duplicate key \"id\""),
            "{deep}"
        );
        let escaped = refused(r#"{"a": {"t\u0069ck": 1, "tick": 2}}"#);
        assert!(
            escaped.starts_with("a: duplicate key \"tick\""),
            "{escaped}"
        );
    }

    #[test]
    fn trailing_text_and_broken_json_are_refused() {
        for text in ["{} {}", "{\"a\": ", "", "[1,]"] {
            assert!(
                matches!(parse(text.as_bytes()), Err(Refused::Malformed(_))),
                "{text}"
            );
        }
    }
}
