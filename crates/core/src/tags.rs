//! Constant strings on the wire: a message's `type`, an object's `kind`, an agent's
//! `"controller": "bot"`. Each is a unit type that serialises as its string and whose
//! JSON Schema is `{"const": ...}`, so a struct that carries one says in its type, and in
//! the schema generated from it, exactly which string it sends.
//!
//! A tag is a field like any other, so it sits where its struct declares it. That is
//! what keeps frames byte for byte as protocol 2 wrote them: they were built as
//! `serde_json::Value`s, whose maps sort their keys, so `kind` came between the other
//! keys of an event rather than first, which is where serde's `#[serde(tag)]` puts it.
//! So an event is a struct with its `kind` among its fields, in alphabetical order, and
//! the events of a sport are an untagged enum of those structs (`one_of` gives its
//! schema): serde derives both their bytes and their schema from that one declaration.

/// Declares unit types, each serialising as its string, with `{"const": ...}` as its
/// schema.
macro_rules! tags {
    ($($(#[$doc:meta])* $name:ident = $value:literal;)*) => {$(
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
        pub struct $name;

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str($value)
            }
        }

        impl schemars::JsonSchema for $name {
            fn inline_schema() -> bool {
                true
            }

            fn schema_name() -> std::borrow::Cow<'static, str> {
                stringify!($name).into()
            }

            fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
                schemars::json_schema!({"const": $value})
            }
        }
    )*};
}

tags! {
    /// `"type": "hello"`.
    Hello = "hello";
    /// `"type": "frame"`.
    Frame = "frame";
    /// `"type": "perception"`.
    Perception = "perception";
    /// `"type": "end"`.
    End = "end";
    /// `"type": "error"`.
    Error = "error";
    /// `"protocol": "fieldhouse"`: what a client is talking to.
    Fieldhouse = "fieldhouse";
    /// `"controller": "bot"`: a connected bot moves the agent. Absent while its built-in
    /// brain does: that is the usual case, and frames go to every spectator 30 times a
    /// second (the word was a tenth of a basketball frame).
    Bot = "bot";
    /// A fielder's `"team": "fielding"`.
    Fielding = "fielding";
    /// `"kind": "baseball"`.
    Baseball = "baseball";
    /// `"kind": "cricket"`.
    Cricket = "cricket";
    /// `"kind": "basketball"`.
    Basketball = "basketball";
    /// A replay's `"record": "header"`.
    Header = "header";
    /// A replay's `"record": "footer"`.
    Footer = "footer";
    /// A replay's `"record": "command"`.
    Command = "command";
    /// A replay's `"record": "control"`.
    Control = "control";
    /// A fly-ball event's `"kind": "launch"`.
    Launch = "launch";
    /// A fly-ball event's `"kind": "caught"`.
    Caught = "caught";
    /// A fly-ball event's `"kind": "landed"`.
    Landed = "landed";
    /// A basketball event's `"kind": "decision"`.
    Decision = "decision";
    /// A basketball event's `"kind": "pass"`.
    Pass = "pass";
    /// A basketball event's `"kind": "pass_caught"`.
    PassCaught = "pass_caught";
    /// A basketball event's `"kind": "shot"`.
    Shot = "shot";
    /// A basketball event's `"kind": "possession_ended"`.
    PossessionEnded = "possession_ended";
}

/// `Some(Bot)` while a bot controls the agent.
pub fn controller(by_bot: bool) -> Option<Bot> {
    by_bot.then_some(Bot)
}

/// The schema of an untagged enum whose variants carry different tags (events, each with
/// its `kind`): exactly one variant matches any message, so it says `oneOf` where
/// schemars, which cannot know the tags exclude each other, says `anyOf`.
pub(crate) fn one_of(schema: &mut schemars::Schema) {
    if let Some(variants) = schema.remove("anyOf") {
        schema.insert("oneOf".into(), variants);
    }
}
