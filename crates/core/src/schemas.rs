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

/// The draft 2020-12 schema of `T`, with its `$id`, tidied for people ([`tidy`]).
fn schema_of<T: JsonSchema>(name: &str) -> Value {
    let mut settings = SchemaSettings::draft2020_12();
    settings.meta_schema = Some("https://json-schema.org/draft/2020-12/schema".into());
    let schema: Schema = settings.into_generator().into_root_schema_for::<T>();
    let mut value = schema.to_value();
    tidy(&mut value);
    let object = value.as_object_mut().expect("a root schema is an object");
    object.insert("$id".into(), format!("{BASE_ID}{name}.schema.json").into());
    value
}

/// Descriptions come from doc comments, wrapped at 90 columns: their lines are joined
/// (a blank line stays a paragraph break). Rust's number formats (`double`, `uint64`)
/// go: they are not JSON Schema's, and the ranges they imply are stated as `minimum`.
fn tidy(value: &mut Value) {
    match value {
        Value::Object(fields) => {
            fields.remove("format");
            if let Some(Value::String(text)) = fields.get_mut("description") {
                *text = text
                    .split("\n\n")
                    .map(|paragraph| paragraph.split('\n').collect::<Vec<_>>().join(" "))
                    .collect::<Vec<_>>()
                    .join("\n\n");
            }
            fields.values_mut().for_each(tidy);
        }
        Value::Array(items) => items.iter_mut().for_each(tidy),
        _ => {}
    }
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
    use serde_json::Value;
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

    /// The schema called `name`, or one of its definitions (`name#Def`), as a validator.
    fn validator(name: &str) -> jsonschema::Validator {
        let (file, def) = name
            .split_once('#')
            .map_or((name, None), |(f, d)| (f, Some(d)));
        let (_, mut schema) = all().into_iter().find(|(n, _)| *n == file).unwrap();
        if let Some(def) = def {
            schema["$ref"] = format!("#/$defs/{def}").into();
            for key in ["properties", "required", "type", "title", "oneOf", "anyOf"] {
                schema.as_object_mut().unwrap().remove(key);
            }
        }
        jsonschema::draft202012::new(&schema).unwrap()
    }

    /// What schema an example of PROTOCOL.md is an instance of: a message by its
    /// `type`, a scenario by its `sport`, a perception's content by its keys; `None` for
    /// what is not a message (REST answers, fragments).
    fn schema_for(example: &Value) -> Option<String> {
        let has = |key: &str| example.get(key).is_some();
        if let Some(kind) = example["type"].as_str() {
            Some(kind.to_string())
        } else if has("sport") {
            Some("scenario".into())
        } else if has("self") && has("ball_in_play") {
            Some("perception#FielderPerception".into())
        } else if has("self") && has("has_ball") {
            Some("perception#PlayerPerception".into())
        } else {
            None
        }
    }

    #[test]
    fn the_protocol_guide_s_examples_are_valid_messages() {
        let guide = std::fs::read_to_string(proto_dir().join("../PROTOCOL.md")).unwrap();
        let mut checked = Vec::new();
        for block in guide.split("```json").skip(1) {
            let block = block.split("```").next().unwrap();
            let examples: Result<Vec<Value>, _> = serde_json::Deserializer::from_str(block)
                .into_iter()
                .collect();
            let Ok(examples) = examples else {
                // Only an illustration may be cut short, never a message.
                assert!(
                    block.contains('…') && !block.contains("\"type\""),
                    "an example that does not parse: {block}"
                );
                continue;
            };
            for example in examples {
                let Some(name) = schema_for(&example) else {
                    continue;
                };
                let errors: Vec<String> = validator(&name)
                    .iter_errors(&example)
                    .map(|e| format!("{e} at {}", e.instance_path))
                    .collect();
                assert!(errors.is_empty(), "{name}: {errors:?} in {example}");
                checked.push(name);
            }
        }
        for name in [
            "hello",
            "frame",
            "perception",
            "end",
            "error",
            "command",
            "control",
        ] {
            assert!(
                checked.iter().any(|c| c == name),
                "no {name} example: {checked:?}"
            );
        }
        assert!(checked.len() >= 15, "{checked:?}");
    }

    #[test]
    fn the_schemas_refuse_what_the_protocol_never_sends() {
        let frame = validator("frame");
        let good = serde_json::json!({"type": "frame", "match": "m", "tick": 1, "time_s": 0.017,
            "ball": {"position": [0.0, 1.0, 0.0], "state": "dead"},
            "agents": [{"heading": 0.2, "id": "lf", "position": [1.0, 2.0], "speed": 0.0, "strategy": "chapman"}],
            "score": {"balls": 0, "caught": 0, "dropped": 0}, "events": []});
        assert!(frame.is_valid(&good));
        for (pointer, wrong) in [
            ("/type", Value::from("frames")),
            ("/ball/state", "flying".into()),
            ("/agents/0/position", serde_json::json!([1.0])),
            ("/agents/0/controller", "builtin".into()),
            ("/tick", (-1).into()),
        ] {
            let mut bad = good.clone();
            match bad.pointer_mut(pointer) {
                Some(v) => *v = wrong,
                None => bad["agents"][0]["controller"] = wrong,
            }
            assert!(!frame.is_valid(&bad), "{pointer} accepted in {bad}");
        }
        let command = validator("command");
        assert!(command.is_valid(
            &serde_json::json!({"type": "command", "tick": 3, "action": {"kind": "stand"}})
        ));
        assert!(!command.is_valid(&serde_json::json!({"type": "command", "tick": 3, "action": {"kind": "stand"}, "extra": 1})));
        assert!(!command.is_valid(
            &serde_json::json!({"type": "command", "tick": 3, "action": {"kind": "fly"}})
        ));
    }

    #[test]
    fn every_schema_is_a_valid_draft_2020_12_schema() {
        for (name, schema) in all() {
            jsonschema::draft202012::new(&schema).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
