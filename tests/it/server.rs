//! The match server as users meet it: the real binary on a loopback port, real HTTP and
//! real WebSockets, traffic checked against the JSON Schemas in proto/.

use crate::common;

use common::server::*;
use common::until;
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use std::io::Read;
use std::process::Command;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::Message;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn demo_matches_are_listed_and_stream_schema_valid_frames() {
    let server = Server::start(&[]);
    let list = server.get("/api/matches");
    let sports: Vec<&str> = list["matches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["sport"].as_str().unwrap())
        .collect();
    for sport in ["baseball", "cricket", "basketball"] {
        assert!(sports.contains(&sport), "{sport} demo missing: {list}");
    }
    for m in list["matches"].as_array().unwrap() {
        let id = m["id"].as_str().unwrap();
        // The lobby's score is the newest frame's.
        let score_keys: Vec<&String> = m["score"].as_object().unwrap().keys().collect();
        let expected = if m["sport"] == "basketball" {
            ["points", "possession", "shot_clock_s"].as_slice()
        } else {
            ["balls", "caught", "dropped"].as_slice()
        };
        assert_eq!(score_keys, expected, "{m}");
        let mut socket = connect(&server.ws(&format!("/ws/matches/{id}"))).await;
        let hello = next(&mut socket).await;
        assert_eq!(hello["type"], "hello");
        assert_eq!(
            (hello["protocol"].as_str(), hello["version"].as_u64()),
            (Some("fieldhouse"), Some(3))
        );
        assert_eq!(hello["role"], "spectator");
        // Basketball moves with the embedded capture by default, named in words without
        // any path of the server's; fly balls say they use no motion capture.
        let source = hello["match"]["motion_source"].as_str().unwrap();
        if m["sport"] == "basketball" {
            assert!(
                source.starts_with("CMU motion capture, embedded: ") && !source.contains('/'),
                "{source}"
            );
        } else {
            assert_eq!(source, fieldhouse::sim::NO_MOTION);
        }
        assert_eq!(m["motion_source"].as_str(), Some(source), "{m}");
        assert_valid(&hello);
        if m["sport"] != "basketball" {
            assert_eq!(hello["match"]["field"]["eye_height_m"], 1.7);
        }
        let mut last = None;
        for _ in 0..8 {
            let frame = next(&mut socket).await;
            assert_eq!(frame["type"], "frame");
            assert_valid(&frame);
            let tick = frame["tick"].as_u64().unwrap();
            assert!(
                last.is_none_or(|l| tick > l),
                "ticks increase: {last:?} then {tick}"
            );
            last = Some(tick);
        }
    }
    let metrics = ureq::get(&server.http("/metrics"))
        .call()
        .unwrap()
        .into_string()
        .unwrap();
    assert!(metrics.contains("fieldhouse_ticks_total"));
    assert!(metrics.contains("fieldhouse_tick_duration_seconds_bucket"));
}

/// Whether a bot controls agent `agent` of match `id`, as the API says.
fn bot_controls(server: &Server, id: &str, agent: &str) -> bool {
    let doc = server.get(&format!("/api/matches/{id}"));
    doc["agents"]
        .as_array()
        .unwrap()
        .iter()
        .any(|a| a["id"] == agent && a["controller"] == "bot")
}

fn agent<'a>(frame: &'a Value, id: &str) -> &'a Value {
    frame["agents"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["id"] == id)
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_connection_with_a_bots_token_takes_over_and_the_first_is_told_and_closed() {
    let server = Server::start(&["--no-demo"]);
    let (id, token, mut first) = server.play_cf("realtime", 1000).await;
    next_of(&mut first, "perception").await;
    let mut second = connect(&server.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
    assert_eq!(next_of(&mut second, "hello").await["role"], "bot");
    let told = next_of(&mut first, "error").await;
    assert_eq!(told["code"], "replaced", "{told}");
    let closed = loop {
        match tokio::time::timeout(Duration::from_secs(5), first.next()).await {
            Ok(Some(Ok(Message::Close(Some(frame))))) => break frame.code,
            Ok(Some(Ok(_))) => {}
            other => panic!("the replaced connection: {other:?}"),
        }
    };
    assert_eq!(closed, CloseCode::Policy);
    // The new connection has the agent.
    next_of(&mut second, "perception").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bots_commands_move_its_agent_and_a_disconnect_hands_it_back() {
    let server = Server::start(&["--no-demo"]);
    let (id, token, mut bot) = server.play_cf("realtime", 1000).await;
    let hello = next(&mut bot).await;
    assert_eq!(
        (hello["role"].as_str(), hello["agent"].as_str()),
        (Some("bot"), Some("cf"))
    );
    assert_valid(&hello);
    let mut spectator = connect(&server.ws(&format!("/ws/matches/{id}"))).await;
    next_of(&mut spectator, "frame").await;
    // Run 12 m toward the batter's side of the field, answering every perception,
    // until the agent is there: within 4 s of play (240 ticks).
    let target = [60.0, 48.0];
    let mut first_tick = None;
    let last_tick = loop {
        let p = next_of(&mut bot, "perception").await;
        let last_tick = p["tick"].as_u64().unwrap();
        let first = *first_tick.get_or_insert(last_tick);
        assert_valid(&p);
        assert_eq!(p["agent"], "cf");
        let at = &p["perception"]["self"]["position"];
        let (x, z) = (at[0].as_f64().unwrap(), at[1].as_f64().unwrap());
        let gap = (x - target[0]).hypot(z - target[1]);
        if gap < 2.0 {
            break last_tick;
        }
        assert!(
            last_tick - first <= 240,
            "cf is {gap} m from its target after 4 s of play"
        );
        let command = json!({"type": "command", "tick": p["tick"], "action": {"kind": "run_to", "target": target}});
        assert_valid(&command);
        bot.send(Message::Text(command.to_string().into()))
            .await
            .unwrap();
    };
    // The spectator was not read meanwhile: skip to a frame of now.
    let frame = loop {
        let frame = next_of(&mut spectator, "frame").await;
        if frame["tick"].as_u64().unwrap() >= last_tick {
            break frame;
        }
    };
    let cf = agent(&frame, "cf");
    assert_eq!(cf["controller"], "bot");
    let at = [
        cf["position"][0].as_f64().unwrap(),
        cf["position"][1].as_f64().unwrap(),
    ];
    let gap = (at[0] - target[0]).hypot(at[1] - target[1]);
    assert!(gap < 2.0, "cf is {gap} m from its target: {at:?}");
    // The token controls only cf: the other fielder is still the server's, which frames
    // leave unsaid.
    assert!(agent(&frame, "rf").get("controller").is_none(), "{frame}");
    drop(bot);
    until(Duration::from_secs(5), "cf was not handed back", || {
        !bot_controls(&server, &id, "cf")
    })
    .await;
    // Reconnecting with the same token resumes control.
    let mut again = connect(&server.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
    assert_eq!(next(&mut again).await["agent"], "cf");
    next_of(&mut again, "perception").await;
    // The API says who plays each agent as the newest frame does: by the next frame.
    until(Duration::from_secs(5), "cf was not taken back", || {
        bot_controls(&server, &id, "cf")
    })
    .await;
}

/// Lock-step over real sockets: the bot's answers reach the match task and play its
/// ticks, and a silent bot's match goes on at the deadline. (How long a tick waits, to
/// the millisecond, is the driver's unit tests', with injected time.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lockstep_advances_only_when_the_bot_answers_or_at_the_deadline() {
    let server = Server::start(&["--no-demo"]);
    // A deadline of a minute: every tick here is played by an answer, or the next
    // perception would not come within `next`'s 10 s.
    let (id, _, mut bot) = server.play_cf("lockstep", 60_000).await;
    next(&mut bot).await;
    let first = next_of(&mut bot, "perception").await["tick"]
        .as_u64()
        .unwrap();
    let mut tick = first;
    while tick < first + 120 {
        let command = json!({"type": "command", "tick": tick, "action": {"kind": "stand"}});
        bot.send(Message::Text(command.to_string().into()))
            .await
            .unwrap();
        let next = next_of(&mut bot, "perception").await["tick"]
            .as_u64()
            .unwrap();
        assert_eq!(next, tick + 1, "lock-step perceives every tick");
        tick = next;
    }
    // Not answered, the last perception's tick holds the match.
    assert_eq!(server.tick(&id), tick);
    // Silent, with a short deadline: the match still goes on, a tick at a time.
    let (_, _, mut silent) = server.play_cf("lockstep", 50).await;
    next(&mut silent).await;
    let mut tick = next_of(&mut silent, "perception").await["tick"]
        .as_u64()
        .unwrap();
    for _ in 0..3 {
        let next = next_of(&mut silent, "perception").await["tick"]
            .as_u64()
            .unwrap();
        assert_eq!(next, tick + 1);
        tick = next;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_wrong_or_missing_token_is_refused_before_the_upgrade() {
    let server = Server::start(&["--no-demo"]);
    let (id, tokens) = server.create(fielder_with_bot("realtime", 1000));
    let (other, _) = server.create(fielder_with_bot("realtime", 1000));
    let status = |result: Result<_, tokio_tungstenite::tungstenite::Error>| match result {
        Err(tokio_tungstenite::tungstenite::Error::Http(response)) => response.status().as_u16(),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("the upgrade succeeded"),
    };
    let play = |m: &str, token: Option<&str>| {
        let query = token.map(|t| format!("?token={t}")).unwrap_or_default();
        server.ws(&format!("/ws/matches/{m}/play{query}"))
    };
    assert_eq!(
        status(tokio_tungstenite::connect_async(play(&id, None)).await),
        401
    );
    assert_eq!(
        status(
            tokio_tungstenite::connect_async(play(&id, Some("0123456789abcdef0123456789abcdef")))
                .await
        ),
        403
    );
    // A token controls only its own match's agent.
    let token = tokens["cf"].as_str().unwrap();
    assert_eq!(
        status(tokio_tungstenite::connect_async(play(&other, Some(token))).await),
        403
    );
    assert_eq!(
        status(tokio_tungstenite::connect_async(play("nope", Some(token))).await),
        404
    );
    // And the right one gets in.
    assert!(tokio_tungstenite::connect_async(play(&id, Some(token)))
        .await
        .is_ok());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn malformed_input_gets_an_error_and_the_match_keeps_ticking() {
    let server = Server::start(&["--no-demo"]);
    let (id, _, mut bot) = server.play_cf("realtime", 1000).await;
    next(&mut bot).await;
    let before = server.tick(&id);
    for (sent, code) in [
        (Message::Text("{not json".into()), "malformed_json"),
        (
            Message::Text(r#"{"type":"teleport"}"#.into()),
            "bad_message",
        ),
        (
            Message::Text(r#"{"type":"command","tick":"soon","action":{"kind":"stand"}}"#.into()),
            "bad_message",
        ),
        (
            Message::Text(
                r#"{"type":"command","tick":1,"action":{"kind":"run_to","target":[1e400,0]}}"#
                    .into(),
            ),
            // Beyond any f64: serde_json refuses the number itself.
            "malformed_json",
        ),
        (
            Message::Text(r#"["command",5,{"kind":"stand"}]"#.into()),
            "bad_message",
        ),
        (Message::Binary(vec![1, 2, 3].into()), "binary"),
    ] {
        bot.send(sent).await.unwrap();
        let error = next_of(&mut bot, "error").await;
        assert_eq!(error["code"], code, "{error}");
        assert_valid(&error);
    }
    // A well-formed command the sport cannot do is rejected with the reason.
    let tick = next_of(&mut bot, "perception").await["tick"].clone();
    let shoot = json!({"type": "command", "tick": tick, "action": {"kind": "shoot"}});
    bot.send(Message::Text(shoot.to_string().into()))
        .await
        .unwrap();
    let error = next_of(&mut bot, "error").await;
    assert_eq!(error["code"], "rejected");
    assert!(error["message"]
        .as_str()
        .unwrap()
        .contains("not a baseball action"));
    // Tick 0 is stale once the match is past tick 4 (perceptions every tick).
    while next_of(&mut bot, "perception").await["tick"]
        .as_u64()
        .unwrap()
        <= 4
    {}
    let stale = json!({"type": "command", "tick": 0, "action": {"kind": "stand"}});
    bot.send(Message::Text(stale.to_string().into()))
        .await
        .unwrap();
    assert_eq!(next_of(&mut bot, "error").await["code"], "stale_tick");
    // The socket is still open and the match still ticks.
    assert_eq!(next_of(&mut bot, "perception").await["agent"], "cf");
    assert!(server.tick(&id) > before);
    // A message over the limit closes the socket with 1009.
    let big = format!("{{\"type\":\"command\",\"pad\":\"{}\"}}", "x".repeat(5000));
    bot.send(Message::Text(big.into())).await.unwrap();
    let code = loop {
        match tokio::time::timeout(Duration::from_secs(5), bot.next())
            .await
            .expect("closed in time")
        {
            Some(Ok(Message::Close(Some(frame)))) => break Some(frame.code),
            Some(Ok(_)) => continue,
            _ => break None,
        }
    };
    assert_eq!(code, Some(CloseCode::Size));
    assert!(server.tick(&id) > before);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slow_spectator_does_not_slow_a_fast_one() {
    let server = Server::start(&["--no-demo"]);
    let (id, _) = server.create(json!({"sport": "cricket"}));
    // Opened and never read: its frames pile up in the socket buffers.
    let _slow = connect(&server.ws(&format!("/ws/matches/{id}"))).await;
    let mut fast = connect(&server.ws(&format!("/ws/matches/{id}"))).await;
    next(&mut fast).await;
    let (started, first) = (
        Instant::now(),
        next(&mut fast).await["tick"].as_u64().unwrap(),
    );
    let mut frames = 0;
    let mut last = first;
    while started.elapsed() < Duration::from_secs(3) {
        let frame = next_of(&mut fast, "frame").await;
        let tick = frame["tick"].as_u64().unwrap();
        assert!(tick > last);
        last = tick;
        frames += 1;
    }
    // 30 frames a second for 3 s; a spectator that kept up got nearly all.
    assert!(frames >= 80, "only {frames} frames in 3 s");
    assert!(
        last - first >= 170,
        "the match ran {} ticks in 3 s",
        last - first
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[allow(clippy::result_large_err)] // ureq's error carries the whole response
async fn rest_errors_are_json_with_the_right_status() {
    // A small body limit (from a config file): an over-limit body is then small enough
    // for the client to finish writing before the server answers 413.
    let config = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("small-bodies.toml");
    std::fs::write(&config, "max_body_bytes = 2048\n").unwrap();
    let server = Server::start(&["--no-demo", "--config", config.to_str().unwrap()]);
    let error = |result: Result<ureq::Response, ureq::Error>| match result {
        Err(ureq::Error::Status(code, response)) => (code, response.into_json::<Value>().unwrap()),
        other => panic!("expected an error status, got {other:?}"),
    };
    let post = |auth: Option<&str>, body: &str| {
        let mut request =
            ureq::post(&server.http("/api/matches")).set("content-type", "application/json");
        if let Some(a) = auth {
            request = request.set("Authorization", a);
        }
        request.send_string(body)
    };
    let (code, body) = error(post(None, r#"{"sport":"baseball"}"#));
    assert_eq!(
        (code, body["error"]["code"].as_str()),
        (401, Some("unauthorized"))
    );
    let (code, body) = error(post(
        Some("Bearer not-the-token"),
        r#"{"sport":"baseball"}"#,
    ));
    assert_eq!(code, 403);
    // The refusal says where this server's token comes from.
    assert_eq!(
        body["error"]["message"],
        "wrong admin token: this server's is the FIELDHOUSE_ADMIN_TOKEN it was started with"
    );
    let admin = format!("Bearer {ADMIN}");
    let (code, body) = error(post(
        Some(&admin),
        r#"{"sport":"baseball","agents":[{"id":"a"},{"id":"b","strategy":"lott"}]}"#,
    ));
    assert_eq!(code, 422);
    let message = body["error"]["message"].as_str().unwrap();
    assert!(
        message.starts_with("agents[1].strategy: unknown strategy \"lott\""),
        "{message}"
    );
    let (code, body) = error(post(Some(&admin), r#"{"sport":"curling"}"#));
    assert_eq!(code, 422);
    assert!(
        body["error"]["message"]
            .as_str()
            .unwrap()
            .starts_with("sport:"),
        "{body}"
    );
    let (code, _) = error(post(Some(&admin), "{not json"));
    assert_eq!(code, 422);
    let (code, body) = error(post(Some(&admin), r#"[null, "baseball"]"#));
    assert_eq!(code, 422);
    assert!(body["error"]["message"]
        .as_str()
        .unwrap()
        .contains("object"));
    // Errors the framework raises are JSON too.
    let (code, body) = error(post(
        Some(&admin),
        &format!("{{\"name\": \"{}\"}}", "x".repeat(4000)),
    ));
    assert_eq!(
        (code, body["error"]["code"].as_str()),
        (413, Some("too_large"))
    );
    let (code, body) = error(ureq::put(&server.http("/api/matches")).call());
    assert_eq!(
        (code, body["error"]["code"].as_str()),
        (405, Some("method_not_allowed"))
    );
    let (code, _) = error(ureq::get(&server.http("/api/matches/nope")).call());
    assert_eq!(code, 404);
    // Deleting ends the match for its spectators.
    let (id, _) = server.create(json!({"sport": "baseball"}));
    let mut spectator = connect(&server.ws(&format!("/ws/matches/{id}"))).await;
    next(&mut spectator).await;
    let (code, _) = error(ureq::delete(&server.http(&format!("/api/matches/{id}"))).call());
    assert_eq!(code, 401);
    ureq::delete(&server.http(&format!("/api/matches/{id}")))
        .set("Authorization", &admin)
        .call()
        .unwrap();
    let end = next_of(&mut spectator, "end").await;
    assert_eq!(end["reason"], "deleted");
    assert_valid(&end);
    let (code, _) = error(ureq::get(&server.http(&format!("/api/matches/{id}"))).call());
    assert_eq!(code, 404);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_ends_matches_and_closes_sockets_with_1001() {
    let mut server = Server::start(&[]);
    let mut spectator = connect(&server.ws("/ws/matches/demo-basketball")).await;
    next(&mut spectator).await;
    let status = Command::new("kill")
        .args(["-TERM", &server.child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let (mut end, mut code) = (None, None);
    while let Ok(Some(Ok(message))) =
        tokio::time::timeout(Duration::from_secs(5), spectator.next()).await
    {
        match message {
            Message::Text(t) => {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["type"] == "end" {
                    end = Some(v);
                }
            }
            Message::Close(frame) => {
                code = frame.map(|f| f.code);
                break;
            }
            _ => {}
        }
    }
    assert_eq!(end.expect("an end message")["reason"], "shutdown");
    assert_eq!(code, Some(CloseCode::Away));
    let exit = server.child.wait().unwrap();
    assert!(exit.success(), "{exit:?}");
}

#[test]
fn every_example_scenario_is_a_valid_body() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let validator = schema("scenario");
    let mut sports = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let body: Value =
            toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let errors: Vec<String> = validator
            .iter_errors(&body)
            .map(|e| e.to_string())
            .collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
        let scenario = fieldhouse::sim::Scenario::from_json(body.to_string().as_bytes())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        sports.push(scenario.sport);
    }
    for sport in [
        fieldhouse::sim::Sport::Baseball,
        fieldhouse::sim::Sport::Cricket,
        fieldhouse::sim::Sport::Basketball,
    ] {
        assert!(sports.contains(&sport), "no example for {sport:?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flooding_is_rate_limited_then_closed_with_1008() {
    let server = Server::start(&["--no-demo"]);
    let (id, _, mut bot) = server.play_cf("realtime", 1000).await;
    next(&mut bot).await;
    let stand = json!({"type": "command", "tick": 0, "action": {"kind": "stand"}}).to_string();
    let (mut sink, mut stream) = bot.split();
    let flood = tokio::spawn(async move {
        for _ in 0..5000 {
            if sink
                .send(Message::Text(stand.clone().into()))
                .await
                .is_err()
            {
                break;
            }
        }
    });
    let (mut limited, mut code) = (false, None);
    while let Ok(Some(Ok(message))) =
        tokio::time::timeout(Duration::from_secs(10), stream.next()).await
    {
        match message {
            Message::Text(t) => {
                limited |= serde_json::from_str::<Value>(&t).unwrap()["code"] == "rate_limited"
            }
            Message::Close(frame) => {
                code = frame.map(|f| f.code);
                break;
            }
            _ => {}
        }
    }
    flood.abort();
    assert!(limited, "no rate_limited error before the close");
    assert_eq!(code, Some(CloseCode::Policy));
    // The match is unharmed.
    let before = server.tick(&id);
    until(Duration::from_secs(5), "the match stopped ticking", || {
        server.tick(&id) > before
    })
    .await;
}

/// A realtime match of `duration_s` whose one fielder, `cf`, a bot plays: its id and
/// bot tokens.
fn realtime_bot_match(server: &Server, duration_s: f64) -> (String, Value) {
    let mut scenario = fielder_with_bot("realtime", 1000);
    scenario["duration_s"] = json!(duration_s);
    scenario["options"]["pause_s"] = json!(0.5);
    server.create(scenario)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_reference_bot_plays_a_match_to_its_end() {
    let server = Server::start(&["--no-demo"]);
    let (id, tokens) = realtime_bot_match(&server, 3.0);
    let output = tokio::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["bot", "--strategy", "chapman", "--url"])
        .arg(server.ws(&format!("/ws/matches/{id}/play")))
        .arg("--token")
        .arg(tokens["cf"].as_str().unwrap())
        .output()
        .await
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let result: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(result["reason"], "finished");
    // A command for every tick of play, give or take the start.
    assert!(result["commands"].as_u64().unwrap() > 120, "{result}");
    assert_eq!(
        result["result"]["balls"].as_u64().map(|b| b >= 1),
        Some(true),
        "{result}"
    );
    // A wrong token is refused with a clear error, before any WebSocket opens.
    let refused = tokio::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["bot", "--token", "wrong", "--url"])
        .arg(server.ws(&format!("/ws/matches/{id}/play")))
        .output()
        .await
        .unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("refused"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_reference_bot_refuses_a_spectator_socket_and_shows_its_progress() {
    let server = Server::start(&["--no-demo"]);
    let (id, tokens) = realtime_bot_match(&server, 7.0);
    let token = tokens["cf"].as_str().unwrap();
    let bot = |url: String, token: Option<&str>| {
        let mut command = tokio::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"));
        command
            .args(["bot", "--url", &url])
            .env_remove("FIELDHOUSE_BOT_TOKEN")
            .env_remove("FIELDHOUSE_LOG");
        if let Some(token) = token {
            command.args(["--token", token]);
        }
        command.kill_on_drop(true).output()
    };
    // The spectators' URL: refused at its hello, naming the play URL, instead of
    // waiting for ever for perceptions that never come.
    let refused = tokio::time::timeout(
        Duration::from_secs(20),
        bot(server.ws(&format!("/ws/matches/{id}")), Some(token)),
    )
    .await
    .expect("the bot gave up at once")
    .unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "{err}");
    assert!(refused.stdout.is_empty());
    assert!(
        err.contains(&server.ws(&format!("/ws/matches/{id}/play"))) && err.contains("--token"),
        "{err}"
    );
    assert!(!err.contains(token), "the token was echoed: {err}");
    // A wrong token is refused before the upgrade, and the bot prints the server's own
    // reason, not the body's bytes.
    let wrong = bot(
        server.ws(&format!("/ws/matches/{id}/play")),
        Some("0123456789abcdef0123456789abcdef"),
    )
    .await
    .unwrap();
    let err = String::from_utf8_lossy(&wrong.stderr);
    assert!(!wrong.status.success(), "{err}");
    assert!(
        err.contains("403") && err.contains("this token controls no agent of this match"),
        "{err}"
    );
    assert!(!err.contains("[123,"), "{err}");
    // The play URL with the token in it (no --token): it plays to the end, and says how
    // it goes on stderr every few seconds (the tick and the score) while stdout keeps
    // the one JSON result.
    let played = bot(
        server.ws(&format!("/ws/matches/{id}/play?token={token}")),
        None,
    )
    .await
    .unwrap();
    let log = String::from_utf8_lossy(&played.stderr);
    assert!(played.status.success(), "{log}");
    let result: Value = serde_json::from_slice(&played.stdout).unwrap();
    assert_eq!(result["reason"], "finished", "{result}");
    let progress: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("tick ") && l.contains(" s of play"))
        .collect();
    assert!(!progress.is_empty(), "no progress in:\n{log}");
    assert!(
        progress.iter().any(|l| l.contains(" caught, ")),
        "no score in the progress:\n{log}"
    );
}

fn replays_of(server: &Server) -> Vec<Value> {
    server.get("/api/replays")["replays"]
        .as_array()
        .unwrap()
        .clone()
}

/// Waits until the match's replay is listed complete; returns its id.
async fn finished_replay(server: &Server, match_id: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        if let Some(r) = replays_of(server)
            .into_iter()
            .find(|r| r["match"] == match_id && r["complete"] == true)
        {
            return r["id"].as_str().unwrap().to_string();
        }
        assert!(
            Instant::now() < deadline,
            "no complete replay of {match_id}: {:?}",
            replays_of(server)
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// A replay file's lines (whole chunks, in format 2), as text.
fn decoded(file: &std::path::Path) -> String {
    let (text, _) = fieldhouse::replay::decode(&std::fs::read(file).unwrap()).unwrap();
    String::from_utf8(text).unwrap()
}

/// The whole lines in a replay file's bytes (0 if they are no replay yet).
fn lines_of(bytes: &[u8]) -> usize {
    fieldhouse::replay::decode(bytes)
        .map_or(0, |(text, _)| text.iter().filter(|&&b| b == b'\n').count())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn recorded_matches_are_listed_downloaded_and_played_with_seek() {
    let dir = empty_dir("server-replays");
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let (id, _) = server.create(json!({"sport": "cricket", "mode": "fast", "duration_s": 20.0}));
    let replay = finished_replay(&server, &id).await;
    // Downloaded, it is the file itself (format 2, named and typed so), and it
    // re-simulates exactly.
    let response = ureq::get(&server.http(&format!("/api/replays/{replay}")))
        .call()
        .unwrap();
    assert_eq!(response.header("content-type"), Some("application/zstd"));
    assert_eq!(
        response.header("content-disposition").map(str::to_string),
        Some(format!("attachment; filename=\"{replay}.jsonl.zst\""))
    );
    let mut body = Vec::new();
    std::io::Read::read_to_end(&mut response.into_reader(), &mut body).unwrap();
    assert!(body == std::fs::read(dir.join(format!("{replay}.jsonl.zst"))).unwrap());
    let file = dir.join("downloaded.copy");
    std::fs::write(&file, &body).unwrap();
    common::assert_verifies(&file);
    // Ids cannot reach outside the replay directory.
    for (path, status) in [
        ("/api/replays/..%2F..%2Fetc%2Fpasswd", 400),
        ("/api/replays/nope", 404),
        ("/api/replays/a.b", 400),
    ] {
        match ureq::get(&server.http(path)).call() {
            Err(ureq::Error::Status(code, _)) => assert_eq!(code, status, "{path}"),
            other => panic!("{path}: {other:?}"),
        }
    }
    let mut viewer = connect(&server.ws(&format!("/ws/replays/{replay}"))).await;
    let hello = next(&mut viewer).await;
    assert_eq!(
        (
            hello["role"].as_str(),
            hello["replay"]["complete"].as_bool()
        ),
        (Some("replay"), Some(true))
    );
    assert_valid(&next_of(&mut viewer, "frame").await);
    let control = |v: Value| Message::Text(v.to_string().into());
    // Seeking lands on the requested tick (frames come every second tick).
    for tick in [600u64, 100, 1000] {
        viewer
            .send(control(
                json!({"type": "control", "action": "seek", "tick": tick}),
            ))
            .await
            .unwrap();
        // Frames sent before the seek may still be on the way: skip those.
        let frame = loop {
            let f = next_of(&mut viewer, "frame").await;
            if (tick..=tick + 2).contains(&f["tick"].as_u64().unwrap()) {
                break f;
            }
        };
        assert_eq!(frame["tick"].as_u64(), Some(tick));
    }
    // Paused, nothing comes; speed outside 0.25–8 is an error.
    viewer
        .send(control(json!({"type": "control", "action": "pause"})))
        .await
        .unwrap();
    // Frames sent before the pause may still be on the way: read until 100 ms pass
    // without one.
    while let Ok(Some(Ok(_))) =
        tokio::time::timeout(Duration::from_millis(100), viewer.next()).await
    {}
    assert!(
        tokio::time::timeout(Duration::from_millis(400), viewer.next())
            .await
            .is_err(),
        "frames while paused"
    );
    // A seek with a lead-in sends what led to the tick first, every frame of it in order
    // and at once, paused as it is: 2 s before tick 600 at 30 frames a second.
    viewer
        .send(control(
            json!({"type": "control", "action": "seek", "tick": 600, "lead_in_s": 2.0}),
        ))
        .await
        .unwrap();
    let mut ticks = Vec::new();
    while let Ok(Some(Ok(Message::Text(text)))) =
        tokio::time::timeout(Duration::from_millis(400), viewer.next()).await
    {
        ticks.push(
            serde_json::from_str::<Value>(&text).unwrap()["tick"]
                .as_u64()
                .unwrap(),
        );
    }
    assert_eq!(ticks, (480..=600).step_by(2).collect::<Vec<u64>>());
    viewer
        .send(control(
            json!({"type": "control", "action": "seek", "tick": 600, "lead_in_s": 20.0}),
        ))
        .await
        .unwrap();
    let refused = next_of(&mut viewer, "error").await;
    assert_eq!(
        (refused["code"].as_str(), refused["message"].as_str()),
        (Some("bad_control"), Some("lead_in_s 20 is outside 0 to 15"))
    );
    viewer
        .send(control(
            json!({"type": "control", "action": "speed", "speed": 9.0}),
        ))
        .await
        .unwrap();
    assert_eq!(next_of(&mut viewer, "error").await["code"], "bad_control");
    // At 8× from near the end, the end message follows the last frame.
    viewer
        .send(control(
            json!({"type": "control", "action": "speed", "speed": 8.0}),
        ))
        .await
        .unwrap();
    viewer
        .send(control(
            json!({"type": "control", "action": "seek", "tick": 1150}),
        ))
        .await
        .unwrap();
    viewer
        .send(control(json!({"type": "control", "action": "play"})))
        .await
        .unwrap();
    let end = next_of(&mut viewer, "end").await;
    assert_eq!(end["tick"].as_u64(), Some(1200));
    assert_valid(&end);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_bot_match_verifies_with_its_command_log() {
    let dir = empty_dir("server-bot-replays");
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let (id, _, mut bot) = server.play_cf("realtime", 1000).await;
    next(&mut bot).await;
    let mut k = 0.0;
    for _ in 0..90 {
        let p = next_of(&mut bot, "perception").await;
        k += 0.05;
        let command = json!({"type": "command", "tick": p["tick"], "action": {"kind": "run_to", "target": [60.0 - k, 50.0]}});
        bot.send(Message::Text(command.to_string().into()))
            .await
            .unwrap();
    }
    drop(bot);
    // The departure is logged once the match task has handed cf back.
    until(Duration::from_secs(5), "cf was not handed back", || {
        !bot_controls(&server, &id, "cf")
    })
    .await;
    ureq::delete(&server.http(&format!("/api/matches/{id}")))
        .set("Authorization", &format!("Bearer {ADMIN}"))
        .call()
        .unwrap();
    let replay = finished_replay(&server, &id).await;
    let file = dir.join(format!("{replay}.jsonl.zst"));
    let text = decoded(&file);
    assert!(
        text.contains("\"record\":\"command\""),
        "commands are logged"
    );
    assert!(
        text.contains("\"record\":\"control\""),
        "the bot's arrival and departure are logged"
    );
    common::assert_verifies(&file);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_killed_mid_match_leaves_a_readable_replay() {
    let dir = empty_dir("server-killed");
    let mut server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let (id, _) = server.create(json!({"sport": "baseball"}));
    let file = || {
        std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .find(|p| p.to_string_lossy().contains(&id))
    };
    // Killed once its replay has 30 frames on disk after its header, in whole chunks
    // (and maybe part of the next).
    let lines = |p: std::path::PathBuf| std::fs::read(p).map_or(0, |b| lines_of(&b));
    until(Duration::from_secs(10), "no 30 frames written", || {
        file().map_or(0, lines) > 31
    })
    .await;
    server.child.kill().unwrap(); // SIGKILL
    server.child.wait().unwrap();
    let file = file().unwrap();
    let info: Value = serde_json::from_slice(
        &Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
            .args(["replay", "info", "--json"])
            .arg(&file)
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap();
    assert_eq!(info["complete"], false);
    assert!(info["frames"].as_u64().unwrap() >= 30, "{info}");
    common::assert_verifies_up_to_its_cut(&file);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_basketball_agents_cost_map_is_served_at_its_pose() {
    let server = Server::start(&[]);
    // Let the demo run a little so agents have moved.
    until(Duration::from_secs(10), "the demo does not tick", || {
        server.tick("demo-basketball") >= 30
    })
    .await;
    let map = server.get("/api/matches/demo-basketball/costmap/o1");
    let behaviour = map["behaviour"].as_str().unwrap();
    assert!(["dribble", "run"].contains(&behaviour), "{behaviour}");
    let rows = map["costs_s"].as_array().unwrap();
    let (size, cell) = (
        map["size_m"].as_f64().unwrap(),
        map["cell_m"].as_f64().unwrap(),
    );
    assert_eq!(rows.len(), (size / cell).round() as usize);
    assert_eq!(map["origin"], json!([-size / 2.0, -size / 2.0]));
    assert!(map["pose"]["position"].is_array() && map["pose"]["heading"].is_number());
    // In the agent's frame: 3 m ahead is cheaper than 3 m behind for a forward mover (the
    // paper's point against distance-proportional cost), and the start costs nothing.
    let at = |x: f64, z: f64| {
        let (i, j) = (
            ((z + size / 2.0) / cell) as usize,
            ((x + size / 2.0) / cell) as usize,
        );
        rows[i][j].as_f64()
    };
    assert!(at(3.0, 0.0).unwrap() < at(-3.0, 0.0).unwrap_or(f64::INFINITY));
    assert!(rows
        .iter()
        .flat_map(|r| r.as_array().unwrap())
        .any(|c| c.as_f64() == Some(0.0)));
    // The same map by behaviour, without a pose: what the spectator page downloads once
    // and places at any agent's pose, live or in a replay.
    let by_behaviour = server.get(&format!("/api/costmaps/{behaviour}"));
    assert_eq!(by_behaviour["costs_s"], map["costs_s"]);
    assert_eq!(by_behaviour["origin"], map["origin"]);
    assert!(by_behaviour.get("pose").is_none());
    for (path, code) in [
        ("/api/matches/demo-baseball/costmap/lf", "no_costmap"),
        ("/api/matches/demo-basketball/costmap/zz", "not_found"),
        ("/api/costmaps/swimming", "no_costmap"),
    ] {
        match ureq::get(&server.http(path)).call() {
            Err(ureq::Error::Status(404, r)) => {
                assert_eq!(r.into_json::<Value>().unwrap()["error"]["code"], code)
            }
            other => panic!("{path}: {other:?}"),
        }
    }
}

/// The poses a spectator draws players with: served once per behaviour (revalidated by
/// ETag), indexed by the frames' `node` and `blend`, whose frames stay within 1 KB.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn motion_poses_are_served_once_and_frames_name_them_by_node_and_blend() {
    let server = Server::start(&[]);
    let mut socket = connect(&server.ws("/ws/matches/demo-basketball")).await;
    assert_eq!(next_of(&mut socket, "hello").await["version"], 3);
    // Frames until a player blends across a cut (the CMU graphs cut every second or so).
    let (mut blended, mut largest) = (None, 0);
    for _ in 0..900 {
        let Some(Ok(Message::Text(text))) = socket.next().await else {
            panic!("the socket closed");
        };
        largest = largest.max(text.len());
        let frame: Value = serde_json::from_str(&text).unwrap();
        if let Some(p) = frame["agents"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p.get("blend").is_some())
        {
            assert_valid(&frame);
            blended = Some(p.clone());
            break;
        }
    }
    let player = blended.expect("a player blends across a cut within 30 s");
    assert!(largest <= 1024, "a basketball frame of {largest} bytes");
    let behaviour = player
        .get("graph")
        .unwrap_or(&player["behaviour"])
        .as_str()
        .unwrap();
    let url = server.http(&format!("/api/motion/{behaviour}"));
    let response = ureq::get(&url).call().unwrap();
    assert_eq!(response.header("cache-control"), Some("no-cache"));
    let etag = response.header("etag").unwrap().to_string();
    let poses: Value = response.into_json().unwrap();
    assert_eq!(poses["behaviour"], behaviour);
    let joints = poses["joints"].as_array().unwrap().len();
    assert!(joints >= 20, "a CMU skeleton has 31 joints, not {joints}");
    assert_eq!(poses["parents"].as_array().unwrap().len(), joints);
    let all = poses["poses_mm"].as_array().unwrap();
    let [node, from] = [&player["node"], &player["blend"][0]].map(|n| n.as_u64().unwrap());
    let weight = player["blend"][1].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&weight), "{player}");
    for n in [node, from] {
        let pose = all[n as usize].as_array().expect("the node has a pose");
        assert_eq!(pose.len(), 3 * joints);
        // The root stands on the ground under the hips, about a metre up.
        assert_eq!([&pose[0], &pose[2]], [&json!(0), &json!(0)]);
        assert!((700..1200).contains(&pose[1].as_i64().unwrap()), "{pose:?}");
    }
    // The browser's copy stays good: asked again with its tag, nothing is sent; so too
    // for `*`, a list holding the tag, and the tag marked weak (RFC 9110, 13.1.2).
    for tags in [
        etag.clone(),
        "*".to_string(),
        format!("\"other\", {etag}"),
        format!("W/{etag}"),
    ] {
        let again = ureq::get(&url).set("If-None-Match", &tags).call().unwrap();
        assert_eq!(again.status(), 304, "{tags}");
        assert_eq!(again.into_string().unwrap(), "", "{tags}");
    }
    let stale = ureq::get(&url)
        .set("If-None-Match", "\"other\"")
        .call()
        .unwrap();
    assert_eq!(stale.status(), 200);
    // Gzipped for a client that takes it, and the same document.
    let zipped = ureq::get(&url)
        .set("Accept-Encoding", "br;q=0.5, gzip")
        .call()
        .unwrap();
    assert_eq!(zipped.header("content-encoding"), Some("gzip"));
    let mut compressed = Vec::new();
    zipped.into_reader().read_to_end(&mut compressed).unwrap();
    let mut text = String::new();
    flate2::read::GzDecoder::new(&compressed[..])
        .read_to_string(&mut text)
        .unwrap();
    assert_eq!(serde_json::from_str::<Value>(&text).unwrap(), poses);
    assert!(
        compressed.len() * 3 < text.len(),
        "{} of {}",
        compressed.len(),
        text.len()
    );
    let refused = ureq::get(&url)
        .set("Accept-Encoding", "gzip;q=0, *")
        .call()
        .unwrap();
    assert_eq!(refused.header("content-encoding"), None);
    // Running loops for the fielders come with the run poses, their slide stated.
    let run = server.get("/api/motion/run");
    let strides = run["strides"].as_array().unwrap();
    assert!(!strides.is_empty());
    assert!(strides
        .iter()
        .all(|s| s["foot_slide_m"].as_f64().unwrap() <= 0.10));
    match ureq::get(&server.http("/api/motion/swimming")).call() {
        Err(ureq::Error::Status(404, r)) => {
            assert_eq!(
                r.into_json::<Value>().unwrap()["error"]["code"],
                "no_motion"
            )
        }
        other => panic!("{other:?}"),
    }
}
