//! `fieldhouse bot`: the reference bot, a real network client that plays one agent. A
//! fielder runs one of the core's catching strategies on the perceptions it receives
//! (the same code the server's built-in fielders run); a basketball player follows the
//! `simple` plan (drive, pass when pressed, shoot in range).

use anyhow::{bail, Context};
use clap::Args;
use fieldhouse::fielding::{Body, Brain, Forecast, Limits, StrategyKind};
use fieldhouse::perception::{PerceptionConfig, PerceptionHistory, Sighting};
use fieldhouse::protocol::{PROTOCOL, VERSION};
use futures_util::{SinkExt, StreamExt};
use glam::DVec2;
use serde_json::{json, Value};
use std::io::Write;
use tokio_tungstenite::tungstenite::Message;

#[derive(Args, Debug)]
#[command(
    after_help = "Example: fieldhouse bot --url ws://127.0.0.1:7878/ws/matches/ID/play --token T --strategy chapman"
)]
pub struct BotArgs {
    /// The agent's play endpoint, ws://HOST:PORT/ws/matches/ID/play.
    #[arg(long)]
    url: String,
    /// The bot token `POST /api/matches` returned for the agent.
    #[arg(long, env = "FIELDHOUSE_BOT_TOKEN")]
    token: String,
    /// Fielders: chapman, chapman-1d, lot, lot-optical. Basketball players play the
    /// simple plan whatever this says.
    #[arg(long, default_value = "chapman")]
    strategy: String,
}

/// A fielder's mind between perceptions.
struct Fielding {
    kind: StrategyKind,
    play: Option<(PerceptionHistory, Brain)>,
}

impl Fielding {
    fn act(&mut self, p: &Value, dt: f64) -> Value {
        let v = |x: &Value| DVec2::new(x[0].as_f64().unwrap_or(0.0), x[1].as_f64().unwrap_or(0.0));
        let optics = &p["optics"];
        if optics.is_null() {
            self.play = None; // between balls: stand and wait
            return json!({"kind": "stand"});
        }
        let limits = Limits {
            max_speed: p["limits"]["max_speed_m_s"].as_f64().unwrap_or(8.5),
            max_accel: p["limits"]["max_accel_m_s2"].as_f64().unwrap_or(4.5),
            ..Limits::HUMAN
        };
        let kind = self.kind;
        let (history, brain) = self.play.get_or_insert_with(|| {
            let forecast = || Forecast {
                point: DVec2::ZERO,
                t: 0.0,
            };
            (
                PerceptionHistory::new(&PerceptionConfig::default(), dt),
                Brain::new(kind, forecast),
            )
        });
        let t = optics["t"].as_f64().unwrap_or(0.0);
        let alpha = optics["alpha"].as_f64().unwrap_or(0.0);
        history.record(Sighting {
            t,
            tan_psi: optics["tan_psi"].as_f64().unwrap_or(0.0),
            toward_ball: DVec2::from_angle(alpha),
            distance: optics["distance_m"].as_f64().unwrap_or(1.0),
        });
        let body = Body {
            pos: v(&p["self"]["position"]),
            vel: v(&p["self"]["velocity"]),
        };
        let accel = match history.percept() {
            Some(percept) if t >= limits.reaction_s => {
                brain.command(&fieldhouse::fielding::strategy::Situation {
                    percept: &percept,
                    body: &body,
                    limits: &limits,
                    home: DVec2::ZERO,
                    t,
                    dt,
                })
            }
            _ => DVec2::ZERO,
        };
        json!({"kind": "accelerate", "accel": accel.to_array()})
    }
}

/// The simple plan from a player's perception of the court.
fn hoops(p: &Value) -> Value {
    let at = |x: &Value| DVec2::new(x[0].as_f64().unwrap_or(0.0), x[1].as_f64().unwrap_or(0.0));
    let me = p["self"].as_str().unwrap_or_default();
    let agents = p["agents"].as_array().cloned().unwrap_or_default();
    let Some(mine) = agents.iter().find(|a| a["id"] == me) else {
        return json!({"kind": "stand"});
    };
    let (pos, team) = (at(&mine["position"]), mine["team"].clone());
    let basket = at(&p["basket"]);
    // The ball is [x, y, z]; on the ground it is at (x, z).
    let b = &p["ball"]["position"];
    let ball = DVec2::new(b[0].as_f64().unwrap_or(0.0), b[2].as_f64().unwrap_or(0.0));
    if team == "defense" {
        return json!({"kind": "move_to", "target": ball.to_array()});
    }
    let nearest_defender = agents
        .iter()
        .filter(|a| a["team"] == "defense")
        .map(|a| at(&a["position"]).distance(pos))
        .fold(f64::INFINITY, f64::min);
    if p["has_ball"] == true {
        if pos.distance(basket) <= 5.0 {
            return json!({"kind": "shoot"});
        }
        if nearest_defender <= 2.0 {
            if let Some(mate) = agents
                .iter()
                .find(|a| a["team"] == "offense" && a["id"] != me)
            {
                return json!({"kind": "pass", "to": mate["id"]});
            }
        }
        return json!({"kind": "move_to", "target": basket.to_array()});
    }
    let spot = basket + DVec2::new(4.0, if pos.y >= 0.0 { 2.5 } else { -2.5 });
    json!({"kind": "move_to", "target": spot.to_array()})
}

pub fn run(args: BotArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let kind: StrategyKind = args.strategy.parse()?;
    if kind == StrategyKind::Predictive {
        bail!("predictive needs the ball's future, which a bot does not perceive; choose chapman, lot-optical, lot or chapman-1d");
    }
    let mut url =
        url::Url::parse(&args.url).with_context(|| format!("\"{}\" is not a URL", args.url))?;
    if !matches!(url.scheme(), "ws" | "wss") {
        bail!("the URL must start with ws:// or wss://");
    }
    url.query_pairs_mut().append_pair("token", &args.token);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let result = runtime.block_on(async move {
        let (mut socket, _) = tokio_tungstenite::connect_async(url.as_str())
            .await
            .context("connecting (a wrong token or match id is refused before the WebSocket opens)")?;
        let mut fielding = Fielding { kind, play: None };
        let mut dt = 1.0 / 60.0;
        let mut sent = 0u64;
        while let Some(message) = socket.next().await {
            let text = match message.context("reading from the server")? {
                Message::Text(t) => t,
                Message::Close(_) => break,
                _ => continue,
            };
            let msg: Value = serde_json::from_str(&text)?;
            match msg["type"].as_str() {
                Some("hello") => {
                    if msg["protocol"] != PROTOCOL || msg["version"] != VERSION {
                        bail!("the server speaks {} {}, this bot {PROTOCOL} {VERSION}", msg["protocol"], msg["version"]);
                    }
                    dt = 1.0 / msg["match"]["tick_hz"].as_f64().unwrap_or(60.0);
                    tracing::info!(agent = %msg["agent"], sport = %msg["match"]["sport"], "playing");
                }
                Some("perception") => {
                    let p = &msg["perception"];
                    let action = if p.get("optics").is_some() {
                        fielding.act(p, dt)
                    } else {
                        hoops(p)
                    };
                    let command = json!({"type": "command", "tick": msg["tick"], "action": action});
                    socket.send(Message::Text(command.to_string().into())).await?;
                    sent += 1;
                }
                Some("error") => tracing::warn!(code = %msg["code"], message = %msg["message"], "server says"),
                Some("end") => return Ok(json!({"result": msg["result"], "reason": msg["reason"], "commands": sent})),
                _ => {}
            }
        }
        Ok(json!({"result": null, "reason": "closed", "commands": sent}))
    })?;
    writeln!(out, "{result}")?;
    Ok(())
}
