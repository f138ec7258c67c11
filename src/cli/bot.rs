//! `fieldhouse bot`: the reference bot, a real network client that plays one agent. A
//! fielder runs one of the core's catching strategies on the perceptions it receives
//! (the same code the server's built-in fielders run); a basketball player follows the
//! `simple` plan (drive, pass when pressed, shoot in range).

use super::run::summary;
use anyhow::{anyhow, bail, Context};
use clap::Args;
use fieldhouse::fielding::{Body, Brain, Forecast, Limits, LotReference, StrategyKind};
use fieldhouse::perception::{PerceptionConfig, PerceptionHistory, Senses, Sighting};
use fieldhouse::protocol::{PROTOCOL, VERSION};
use fieldhouse::words::{figure, plural};
use futures_util::{SinkExt, StreamExt};
use glam::DVec2;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{json, Value};
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::Arc;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;
use url::Url;

/// How often the progress line is written while playing (when stderr is not a
/// terminal; on a terminal it is one line redrawn in place).
const PROGRESS_EVERY: Duration = Duration::from_secs(3);

/// The server says hello at once; a socket that stays silent this long is not one.
const HELLO_WITHIN: Duration = Duration::from_secs(10);

#[derive(Args, Debug)]
#[command(
    after_help = "Plays until the match ends, printing the result as one JSON document on stdout; \
    progress (tick and score) goes to stderr every few seconds.\n\
    Example: fieldhouse bot --url ws://127.0.0.1:7878/ws/matches/ID/play --token T --strategy chapman"
)]
pub(super) struct BotArgs {
    /// The agent's play endpoint, ws://HOST:PORT/ws/matches/ID/play (the spectators'
    /// /ws/matches/ID cannot play). The token may ride in it as ?token=TOKEN instead.
    #[arg(long, value_name = "URL")]
    url: String,
    /// The bot token `POST /api/matches` returned for the agent (its `bot_tokens`
    /// entry); or ?token=TOKEN in the URL.
    #[arg(long, env = "FIELDHOUSE_BOT_TOKEN")]
    token: Option<String>,
    /// Fielders: chapman, chapman-1d, lot, lot-optical. Basketball players play the
    /// simple plan whatever this says.
    #[arg(long, default_value = "chapman")]
    strategy: String,
}

/// A fielder's mind between perceptions.
struct Fielding {
    kind: StrategyKind,
    play: Option<(Senses, PerceptionHistory, Brain)>,
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
        let (senses, history, brain) = self.play.get_or_insert_with(|| {
            let forecast = || Forecast {
                point: DVec2::ZERO,
                t: 0.0,
            };
            // The server's perception is the ideal eye's: angles and distance as they are.
            let eye = PerceptionConfig::default();
            (
                Senses::new(&eye, 0, dt),
                PerceptionHistory::new(&eye, dt),
                Brain::new(kind, LotReference::Apex, forecast),
            )
        });
        let t = optics["t"].as_f64().unwrap_or(0.0);
        let alpha = optics["alpha"].as_f64().unwrap_or(0.0);
        let body = Body {
            pos: v(&p["self"]["position"]),
            vel: v(&p["self"]["velocity"]),
        };
        let seen = Sighting {
            t,
            tan_psi: optics["tan_psi"].as_f64().unwrap_or(0.0),
            toward_ball: DVec2::from_angle(alpha),
            distance: optics["distance_m"].as_f64().unwrap_or(1.0),
        };
        history.record(senses.look(&seen, body.pos, body.vel));
        let accel = match history.percept(body.pos, body.vel, (0.0, 0.0)) {
            Some(percept) if t >= limits.reaction_s => {
                brain.command(&fieldhouse::fielding::strategy::Situation {
                    percept: Some(&percept),
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

/// A refused upgrade in the server's own words (the message of its JSON error body, or
/// the body as text), with the status; any other error as it is.
fn refusal(e: tokio_tungstenite::tungstenite::Error) -> anyhow::Error {
    match e {
        tokio_tungstenite::tungstenite::Error::Http(response) => {
            let body = response
                .body()
                .as_deref()
                .map(String::from_utf8_lossy)
                .unwrap_or_default();
            let said = serde_json::from_str::<Value>(&body)
                .ok()
                .and_then(|v| v["error"]["message"].as_str().map(str::to_string))
                .unwrap_or_else(|| body.into_owned());
            anyhow!("refused with {}: {said}", response.status())
        }
        other => other.into(),
    }
}

pub(super) fn run(args: BotArgs, out: &mut impl Write) -> anyhow::Result<()> {
    let kind: StrategyKind = args.strategy.parse()?;
    if kind == StrategyKind::Predictive {
        bail!("predictive needs the ball's future, which a bot does not perceive; choose chapman, lot-optical, lot or chapman-1d");
    }
    let (url, shown) = play_url(&args.url, args.token.as_deref())?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let result = runtime.block_on(async move {
        let (mut socket, _) = tokio_tungstenite::connect_async(url.as_str())
            .await
            .map_err(refusal)
            .with_context(|| format!("connecting to {shown} (a wrong token or match id is refused before the WebSocket opens)"))?;
        let hello = tokio::time::timeout(HELLO_WITHIN, first_text(&mut socket))
            .await
            .map_err(|_| anyhow!("{shown} said nothing for {} s; a fieldhouse server says hello at once", HELLO_WITHIN.as_secs()))??;
        let dt = check_hello(&hello, &shown)?;
        tracing::info!(agent = %hello["agent"], sport = %hello["match"]["sport"], "playing");
        let played = Arc::new(Played::default());
        let progress = tokio::spawn(show_progress(
            played.clone(),
            status_url(&shown, hello["match"]["id"].as_str().unwrap_or_default()),
        ));
        let mut fielding = Fielding { kind, play: None };
        let mut ended = json!({"result": null, "reason": "closed"});
        while let Some(message) = socket.next().await {
            let text = match message.context("reading from the server")? {
                Message::Text(t) => t,
                Message::Close(_) => break,
                _ => continue,
            };
            let msg: Value = serde_json::from_str(&text)?;
            match msg["type"].as_str() {
                Some("perception") => {
                    let p = &msg["perception"];
                    let action = if p.get("optics").is_some() {
                        fielding.act(p, dt)
                    } else {
                        hoops(p)
                    };
                    let command = json!({"type": "command", "tick": msg["tick"], "action": action});
                    socket.send(Message::Text(command.to_string().into())).await?;
                    played.tick.store(msg["tick"].as_u64().unwrap_or(0), Relaxed);
                    played.time_s.store(msg["time_s"].as_f64().unwrap_or(0.0).to_bits(), Relaxed);
                    played.commands.fetch_add(1, Relaxed);
                }
                Some("error") => tracing::warn!(code = %msg["code"], message = %msg["message"], "server says"),
                Some("end") => {
                    ended = json!({"result": msg["result"], "reason": msg["reason"]});
                    break;
                }
                _ => {}
            }
        }
        progress.abort();
        let _ = progress.await;
        ended["commands"] = json!(played.commands.load(Relaxed));
        anyhow::Ok(ended)
    })?;
    writeln!(out, "{result}")?;
    Ok(())
}

/// The URL to connect to, with the token in its query (from --token, else from the URL
/// as given), and the URL to show in messages, without its query so that no token is
/// echoed.
fn play_url(given: &str, token: Option<&str>) -> anyhow::Result<(Url, Url)> {
    let mut url = Url::parse(given).with_context(|| {
        format!("\"{given}\" is not a URL; write ws://HOST:PORT/ws/matches/ID/play")
    })?;
    if !matches!(url.scheme(), "ws" | "wss") {
        bail!("the URL must start with ws:// or wss:// (ws://HOST:PORT/ws/matches/ID/play)");
    }
    let mut query: Vec<(String, String)> = url.query_pairs().into_owned().collect();
    let in_url = query
        .iter()
        .position(|(k, _)| k == "token")
        .map(|i| query.remove(i).1);
    let token = token.map(str::to_string).or(in_url).ok_or_else(|| {
        anyhow!(
            "no bot token: pass --token TOKEN (the agent's entry in the bot_tokens that \
             POST /api/matches returned), set FIELDHOUSE_BOT_TOKEN, or add ?token=TOKEN to the URL"
        )
    })?;
    let mut shown = url.clone();
    shown.set_query(None);
    url.set_query(None);
    url.query_pairs_mut()
        .extend_pairs(&query)
        .append_pair("token", &token);
    Ok((url, shown))
}

/// The first text message, as JSON.
async fn first_text<S>(socket: &mut S) -> anyhow::Result<Value>
where
    S: StreamExt<Item = Result<Message, tokio_tungstenite::tungstenite::Error>> + Unpin,
{
    while let Some(message) = socket.next().await {
        if let Message::Text(t) = message.context("reading from the server")? {
            return serde_json::from_str(&t).context("the server's first message is not JSON");
        }
    }
    bail!("the server closed the socket before saying hello")
}

/// Checks that the server speaks this protocol and that the socket plays an agent (a
/// spectator's socket says hello too, then only sends frames, which a bot would wait on
/// for ever); returns the tick length.
fn check_hello(hello: &Value, shown: &Url) -> anyhow::Result<f64> {
    if hello["type"] != "hello" || hello["protocol"] != PROTOCOL {
        bail!("{shown} is not a fieldhouse match socket (its first message is not a fieldhouse hello)");
    }
    if hello["version"] != VERSION {
        bail!(
            "the server speaks {PROTOCOL} {}, this bot {PROTOCOL} {VERSION}",
            hello["version"]
        );
    }
    if hello["role"] != "bot" || !hello["agent"].is_string() {
        let role = hello["role"].as_str().unwrap_or("client that is not a bot");
        bail!(
            "{shown} is a {role}'s socket, which watches a match but cannot play in it; a bot \
             connects to its agent's play socket, ws://HOST:PORT/ws/matches/ID/play, with the \
             agent's token: fieldhouse bot --url {} --token TOKEN (or ?token=TOKEN in the URL)",
            play_form(shown)
        );
    }
    Ok(1.0 / hello["match"]["tick_hz"].as_f64().unwrap_or(60.0))
}

/// The play URL a spectator URL (`.../ws/matches/ID`) stands for, or the general form.
fn play_form(spectating: &Url) -> String {
    let path = spectating.path().trim_end_matches('/');
    let is_match = path
        .rsplit_once("/ws/matches/")
        .is_some_and(|(_, id)| !id.is_empty() && !id.contains('/'));
    if is_match {
        let mut url = spectating.clone();
        url.set_path(&format!("{path}/play"));
        url.to_string()
    } else {
        "ws://HOST:PORT/ws/matches/ID/play".to_string()
    }
}

/// Where the match's score can be read over HTTP (`GET /api/matches/ID`, public), from
/// the play URL; None over wss://, which this build's HTTP client does not speak.
fn status_url(play: &Url, id: &str) -> Option<String> {
    let prefix = play
        .path()
        .strip_suffix(&format!("/ws/matches/{id}/play"))?;
    if play.scheme() != "ws" || id.is_empty() {
        return None;
    }
    let host = play.host_str()?;
    let port = play.port_or_known_default()?;
    Some(format!("http://{host}:{port}{prefix}/api/matches/{id}"))
}

/// What the bot has done so far, for the progress line.
#[derive(Default)]
struct Played {
    tick: AtomicU64,
    /// f64 bits of the perception's time_s.
    time_s: AtomicU64,
    commands: AtomicU64,
}

/// Every few seconds: the tick, the commands sent and the score, on stderr; one line
/// redrawn in place on a terminal, else a log line each time. Runs until aborted.
async fn show_progress(played: Arc<Played>, status: Option<String>) {
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {msg}").expect("template is valid"),
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    });
    let mut every = tokio::time::interval(if bar.is_some() {
        Duration::from_secs(1)
    } else {
        PROGRESS_EVERY
    });
    every.tick().await; // the first tick is at once: nothing to show yet
    loop {
        every.tick().await;
        let score = match &status {
            Some(url) => score(url.clone()).await,
            None => None,
        };
        let line = format!(
            "tick {} ({} s of play), {} sent{}",
            played.tick.load(Relaxed),
            figure(f64::from_bits(played.time_s.load(Relaxed)), 1),
            plural(played.commands.load(Relaxed), "command"),
            score.map_or(String::new(), |s| format!("; {}", summary(&s)))
        );
        match &bar {
            Some(bar) => bar.set_message(line),
            None => tracing::info!("{line}"),
        }
    }
}

/// The match's score now, from its status; None if the server does not answer quickly.
async fn score(url: String) -> Option<Value> {
    tokio::task::spawn_blocking(move || {
        let doc: Value = ureq::get(&url)
            .timeout(Duration::from_secs(2))
            .call()
            .ok()?
            .into_json()
            .ok()?;
        Some(doc["score"].clone()).filter(|s| s.is_object())
    })
    .await
    .ok()
    .flatten()
}
