//! The JSON Schemas in `proto/`, generated from the protocol's types: one file per
//! message a client sends or receives, and the scenario a match is made of. They are
//! committed so a bot author can read and validate against them without building the
//! server; a test fails when a committed file differs from what the types generate
//! (`FIELDHOUSE_BLESS=1 cargo test -p fieldhouse-core schemas` rewrites them).

use crate::protocol::{ClientMessage, End, ErrorMessage, Frame, Hello, Perception, ViewerMessage};
use crate::sim::Scenario;
use schemars::generate::SchemaSettings;
use schemars::{JsonSchema, Schema};
use serde_json::Value;

/// Where the schemas are published, as each file's `$id` says.
const BASE_ID: &str = "https://fieldhouse.dev/proto/";

/// Every schema, as `(name, schema)`: the file `proto/<name>.schema.json` holds it.
pub fn all() -> Vec<(&'static str, Value)> {
    vec![
        ("hello", schema_of::<Hello<'static>>("hello")),
        ("frame", schema_of::<Frame<'static>>("frame")),
        ("perception", schema_of::<Perception<'static>>("perception")),
        ("end", schema_of::<End<'static>>("end")),
        ("error", schema_of::<ErrorMessage<'static>>("error")),
        ("command", schema_of::<ClientMessage>("command")),
        ("control", schema_of::<ViewerMessage>("control")),
        ("scenario", schema_of::<Scenario>("scenario")),
    ]
}

/// The draft 2020-12 schema of `T`, with its `$id`; numbers that are `f64` say only
/// `number` (their format, "double", is what JSON numbers are anyway).
fn schema_of<T: JsonSchema>(name: &str) -> Value {
    let mut settings = SchemaSettings::draft2020_12();
    settings.meta_schema = Some("https://json-schema.org/draft/2020-12/schema".into());
    let schema: Schema = settings.into_generator().into_root_schema_for::<T>();
    let mut value = schema.to_value();
    let object = value.as_object_mut().expect("a root schema is an object");
    object.insert("$id".into(), format!("{BASE_ID}{name}.schema.json").into());
    value
}

/// A schema as the committed file holds it: pretty JSON with a final newline.
pub fn to_file_text(schema: &Value) -> String {
    let mut text = serde_json::to_string_pretty(schema).expect("schemas serialise");
    text.push('\n');
    text
}

#[cfg(test)]
mod tests {
    use super::{all, to_file_text};
    use std::path::PathBuf;

    fn proto_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../proto")
    }

    #[test]
    fn the_committed_schemas_are_the_ones_the_types_generate() {
        let bless = std::env::var_os("FIELDHOUSE_BLESS").is_some();
        let mut stale = Vec::new();
        for (name, schema) in all() {
            let path = proto_dir().join(format!("{name}.schema.json"));
            let generated = to_file_text(&schema);
            if bless {
                std::fs::write(&path, &generated).unwrap();
            } else if std::fs::read_to_string(&path).ok().as_deref() != Some(&generated) {
                stale.push(path.display().to_string());
            }
        }
        assert!(
            stale.is_empty(),
            "{stale:?} differ from the protocol's types: run \
             FIELDHOUSE_BLESS=1 cargo test -p fieldhouse-core schemas, and review the diff"
        );
    }

    #[test]
    fn every_schema_is_a_valid_draft_2020_12_schema() {
        for (name, schema) in all() {
            jsonschema::draft202012::new(&schema)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
