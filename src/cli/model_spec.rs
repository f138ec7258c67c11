//! How a user names a model of the defender (`--shot-model`, `--pass-model`), before
//! `basketball-eval` fits one: shared by `basketball-eval` and `basketball-decide` so the
//! two commands take the same names with the same meaning.

use std::str::FromStr;

/// A model of the defender as a user names it, before any fitting: what
/// `basketball-eval --shot-model` and `basketball-decide --shot-model` take.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum ModelSpec {
    Own,
    Maps(String),
    Kinematic,
    Isotropic,
    None,
}

impl ModelSpec {
    /// The name a user writes for it.
    pub(super) fn name(&self) -> String {
        match self {
            ModelSpec::Own => "own".into(),
            ModelSpec::Maps(b) if b == "run" => "paper".into(),
            ModelSpec::Maps(b) => format!("maps:{b}"),
            ModelSpec::Kinematic => "kinematic".into(),
            ModelSpec::Isotropic => "isotropic".into(),
            ModelSpec::None => "none".into(),
        }
    }
}

impl FromStr for ModelSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "own" => Ok(ModelSpec::Own),
            // The paper's model: the shooter's own non-dribbling maps.
            "paper" => Ok(ModelSpec::Maps("run".into())),
            "kinematic" => Ok(ModelSpec::Kinematic),
            "isotropic" => Ok(ModelSpec::Isotropic),
            "none" => Ok(ModelSpec::None),
            _ => match s.strip_prefix("maps:") {
                Some(b) if !b.is_empty() => Ok(ModelSpec::Maps(b.to_string())),
                _ => Err(format!(
                    "unknown defender model \"{s}\"; expected one of own, paper, \
                     maps:BEHAVIOUR, kinematic, isotropic, none"
                )),
            },
        }
    }
}
