//! What an outside attacker found, on the real binary over loopback: numbers
//! that pass validation but kill a match, answers to perceptions charged as flooding,
//! duplicate keys, wrapped ticks, a non-atomic match limit, ended matches listed for
//! ever, an upper-case auth scheme, and a page without a content security policy.

use crate::common;

use common::server::{connect, next, next_of, Server, Socket, ADMIN};
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

/// Posts a scenario body with an `Authorization` header; the status and the JSON body.
fn post(server: &Server, authorization: &str, body: &str) -> (u16, Value) {
    let result = ureq::post(&server.http("/api/matches"))
        .set("content-type", "application/json")
        .set("Authorization", authorization)
        .send_string(body);
    match result {
        Ok(response) => (response.status(), response.into_json().unwrap()),
        Err(ureq::Error::Status(code, response)) => (code, response.into_json().unwrap()),
        Err(e) => panic!("{e}"),
    }
}

/// A server started with a settings file holding `settings`.
fn with_settings(name: &str, settings: &str, extra: &[&str]) -> Server {
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.toml"));
    std::fs::write(&path, settings).unwrap();
    let mut args = vec!["--no-demo", "--config", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    Server::start(&args)
}

async fn send(socket: &mut Socket, message: Value) {
    socket
        .send(Message::Text(message.to_string().into()))
        .await
        .unwrap();
}

fn stand(tick: u64) -> Value {
    json!({"type": "command", "tick": tick, "action": {"kind": "stand"}})
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn time_like_numbers_the_code_cannot_represent_are_refused_with_their_field() {
    let server = Server::start(&["--no-demo"]);
    let bearer = format!("Bearer {ADMIN}");
    for (body, expected) in [
        (
            r#"{"sport":"baseball","tick_hz":1e-300,"frame_hz":1e-300}"#,
            "tick_hz: must be from 1 to 1000, not 1e-300",
        ),
        (
            r#"{"sport":"baseball","tick_hz":0.5,"frame_hz":0.5}"#,
            "tick_hz: must be from 1 to 1000, not 0.5",
        ),
        (
            r#"{"sport":"baseball","frame_hz":5e-324}"#,
            "frame_hz: must be from 0.1 to 60, not 5e-324",
        ),
        (
            r#"{"sport":"cricket","duration_s":1e300}"#,
            "duration_s: must be more than 0",
        ),
        (
            r#"{"sport":"baseball","lockstep_deadline_ms":0}"#,
            "lockstep_deadline_ms: must be from 1 to 60000, not 0",
        ),
    ] {
        let (status, doc) = post(&server, &bearer, body);
        assert_eq!(status, 422, "{body}: {doc}");
        let message = doc["error"]["message"].as_str().unwrap();
        assert!(message.starts_with(expected), "{body}: {message}");
    }
    assert_eq!(server.get("/api/matches")["matches"], json!([]));
    assert_eq!(server.metric("fieldhouse_matches"), 0.0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_response_carries_the_security_headers() {
    let server = Server::start(&["--no-demo"]);
    for path in [
        "/",
        "/web/app.js",
        "/web/lobby.js",
        "/api/matches",
        "/no/such/route",
    ] {
        let response = match ureq::get(&server.http(path)).call() {
            Ok(r) => r,
            Err(ureq::Error::Status(_, r)) => r,
            Err(e) => panic!("{path}: {e}"),
        };
        let csp = response.header("content-security-policy").unwrap_or("");
        for directive in [
            "script-src 'self'",
            "object-src 'none'",
            "frame-ancestors 'none'",
        ] {
            assert!(csp.contains(directive), "{path}: {csp:?}");
        }
        assert!(!csp.contains("unsafe-inline"), "{path}: {csp:?}");
        assert_eq!(
            response.header("x-content-type-options"),
            Some("nosniff"),
            "{path}"
        );
        assert_eq!(
            response.header("referrer-policy"),
            Some("no-referrer"),
            "{path}"
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_bearer_scheme_is_read_in_any_case() {
    let server = Server::start(&["--no-demo"]);
    let body = common::server::fielder_with_bot("realtime", 1000).to_string();
    let (status, doc) = post(&server, &format!("BEARER {ADMIN}"), &body);
    assert_eq!(status, 201, "{doc}");
    let (status, _) = post(&server, &format!("bearer \t {ADMIN}"), &body);
    assert_eq!(status, 201);
    let (status, _) = post(&server, &format!("Basic {ADMIN}"), &body);
    assert_eq!(status, 401);
    // Bot tokens are read the same way.
    let (id, token) = (
        doc["id"].as_str().unwrap(),
        doc["bot_tokens"]["cf"].as_str().unwrap(),
    );
    let mut request =
        tokio_tungstenite::tungstenite::client::IntoClientRequest::into_client_request(
            server.ws(&format!("/ws/matches/{id}/play")),
        )
        .unwrap();
    request
        .headers_mut()
        .insert("authorization", format!("bEaReR {token}").parse().unwrap());
    let (mut bot, _) = tokio_tungstenite::connect_async(request)
        .await
        .expect("the bot is let in");
    assert_eq!(next(&mut bot).await["type"], "hello");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_key_given_twice_is_refused_in_scenarios_and_bot_messages() {
    let server = Server::start(&["--no-demo"]);
    let bearer = format!("Bearer {ADMIN}");
    let (status, doc) = post(
        &server,
        &bearer,
        r#"{"sport":"basketball","sport":"baseball"}"#,
    );
    assert_eq!(status, 422, "{doc}");
    let message = doc["error"]["message"].as_str().unwrap();
    assert!(message.starts_with("duplicate key \"sport\""), "{message}");
    let nested = r#"{"sport":"baseball","agents":[{"id":"cf","bot":true,"bot":false}]}"#;
    let (status, doc) = post(&server, &bearer, nested);
    assert_eq!(status, 422, "{doc}");
    let message = doc["error"]["message"].as_str().unwrap();
    assert!(
        message.starts_with("agents[0]: duplicate key \"bot\""),
        "{message}"
    );

    let (_, _, mut bot) = server.play_cf("realtime", 1000).await;
    next(&mut bot).await;
    let tick = next_of(&mut bot, "perception").await["tick"]
        .as_u64()
        .unwrap();
    let twice =
        format!(r#"{{"type":"command","tick":{tick},"tick":{tick},"action":{{"kind":"stand"}}}}"#);
    bot.send(Message::Text(twice.into())).await.unwrap();
    let error = next_of(&mut bot, "error").await;
    assert_eq!(error["code"], "bad_message", "{error}");
    assert!(error["message"]
        .as_str()
        .unwrap()
        .contains("duplicate key \"tick\""));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ticks_near_the_top_of_u64_are_future_ticks_and_the_match_lives() {
    let server = Server::start(&["--no-demo"]);
    let (id, _, mut bot) = server.play_cf("realtime", 1000).await;
    next(&mut bot).await;
    for tick in [u64::MAX, u64::MAX - 1, u64::MAX - 3] {
        send(&mut bot, stand(tick)).await;
        let error = next_of(&mut bot, "error").await;
        assert_eq!(error["code"], "future_tick", "{tick}: {error}");
    }
    // Old ticks are stale once the match has gone on.
    common::until(
        Duration::from_secs(10),
        "the match never reached tick 30",
        || server.tick(&id) >= 30,
    )
    .await;
    send(&mut bot, stand(0)).await;
    assert_eq!(next_of(&mut bot, "error").await["code"], "stale_tick");
    let summary = server.get(&format!("/api/matches/{id}"));
    assert_eq!(summary["status"], "running");
    let before = server.tick(&id);
    common::until(Duration::from_secs(5), "the match stopped ticking", || {
        server.tick(&id) > before
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn racing_creations_start_exactly_max_matches() {
    let max = 3;
    let server = with_settings("max-three", &format!("max_matches = {max}\n"), &[]);
    let body = json!({"sport": "baseball"}).to_string();
    let statuses: Vec<u16> = std::thread::scope(|s| {
        let racers: Vec<_> = (0..16)
            .map(|_| s.spawn(|| post(&server, &format!("Bearer {ADMIN}"), &body).0))
            .collect();
        racers.into_iter().map(|r| r.join().unwrap()).collect()
    });
    assert_eq!(
        statuses.iter().filter(|&&s| s == 201).count(),
        max,
        "{statuses:?}"
    );
    assert_eq!(
        statuses.iter().filter(|&&s| s == 503).count(),
        16 - max,
        "{statuses:?}"
    );
    assert_eq!(
        server.get("/api/matches")["matches"]
            .as_array()
            .unwrap()
            .len(),
        max
    );
    assert_eq!(server.metric("fieldhouse_matches"), max as f64);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ended_matches_leave_the_list_after_their_time_to_live() {
    let server = Server::start(&["--no-demo", "--ended-match-ttl-s", "1"]);
    let (id, _) = server.create(json!({"sport": "baseball", "mode": "fast", "duration_s": 1.0}));
    let started = Instant::now();
    let (mut seen_ended, mut listed) = (false, Vec::new());
    common::found_within(Duration::from_secs(10), || {
        listed = server.get("/api/matches")["matches"]
            .as_array()
            .unwrap()
            .clone();
        match listed.iter().find(|m| m["id"] == id.as_str()) {
            Some(m) => {
                seen_ended |= m["status"] == "ended";
                None
            }
            None => Some(()),
        }
    })
    .await
    .unwrap_or_else(|| panic!("still listed: {listed:?}"));
    assert!(seen_ended, "listed as ended for a while before it left");
    println!(
        "created, ended and gone from the list in {:?}",
        started.elapsed()
    );
    // ttl (1 s) + the sweep period (1 s) + the match's own run, with slack for a busy
    // machine.
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "{:?}",
        started.elapsed()
    );
    assert_eq!(server.metric("fieldhouse_matches"), 0.0);
}

/// A lock-step match at 1000 Hz with a 5 ms deadline, its bot limited to 20 messages a
/// second (burst 20), and the bot's socket.
async fn fast_lockstep_bot(name: &str) -> (Server, String, Socket) {
    let server = with_settings(name, "bot_messages_per_second = 20\nbot_burst = 20\n", &[]);
    let mut scenario = common::server::fielder_with_bot("lockstep", 5);
    scenario["tick_hz"] = json!(1000.0);
    let (id, tokens) = server.create(scenario);
    let token = tokens["cf"].as_str().unwrap();
    let mut bot = connect(&server.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
    assert_eq!(next(&mut bot).await["type"], "hello");
    (server, id, bot)
}

/// Answers every perception at once with `extra` more messages after each, for
/// `seconds`: the answers sent, and the error codes and close code heard.
async fn answer_every_perception(
    bot: &mut Socket,
    extra: usize,
    seconds: u64,
) -> (u64, Vec<String>, Option<u16>) {
    let until = Instant::now() + Duration::from_secs(seconds);
    let (mut answers, mut errors) = (0, Vec::new());
    while Instant::now() < until {
        let message = match tokio::time::timeout(Duration::from_secs(5), bot.next()).await {
            Ok(Some(Ok(m))) => m,
            other => panic!("the socket went quiet or broke: {other:?}"),
        };
        let text = match message {
            Message::Text(t) => t,
            Message::Close(frame) => return (answers, errors, frame.map(|f| f.code.into())),
            _ => continue,
        };
        let m: Value = serde_json::from_str(&text).unwrap();
        match m["type"].as_str() {
            Some("perception") => {
                let tick = m["tick"].as_u64().unwrap();
                send(bot, stand(tick)).await;
                answers += 1;
                for _ in 0..extra {
                    send(bot, stand(tick)).await;
                }
            }
            Some("error") => errors.push(m["code"].as_str().unwrap().to_string()),
            _ => {}
        }
    }
    (answers, errors, None)
}

/// A lock-step basketball match, `o1` a bot that answers each perception at once: the
/// 14 ticks between its perceptions do not wait for the clock (they ran in real time,
/// four perceptions a second), so its possessions go at the bot's pace.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lockstep_basketball_bot_plays_its_possessions_at_its_own_pace() {
    let server = Server::start(&["--no-demo"]);
    let (id, tokens) = server.create(json!({
        "sport": "basketball",
        "mode": "lockstep",
        "lockstep_deadline_ms": 1000,
        "agents": [
            {"id": "o1", "team": "offense", "strategy": "costmap", "bot": true},
            {"id": "o2", "team": "offense", "strategy": "costmap"},
            {"id": "d1", "team": "defense", "strategy": "defense"}
        ],
        "options": {"possessions": 10}
    }));
    let token = tokens["o1"].as_str().unwrap();
    let mut bot = connect(&server.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
    assert_eq!(next(&mut bot).await["type"], "hello");
    let started = Instant::now();
    let (mut perceptions, mut last) = (0u64, 0u64);
    let end = loop {
        let m = next(&mut bot).await;
        match m["type"].as_str() {
            Some("perception") => {
                let tick = m["tick"].as_u64().unwrap();
                assert!(tick > last, "perceptions in order: {tick} after {last}");
                if perceptions > 0 {
                    assert_eq!(tick - last, 15, "a perception every 15th tick");
                }
                (perceptions, last) = (perceptions + 1, tick);
                send(&mut bot, stand(tick)).await;
            }
            Some("end") => break m,
            _ => {}
        }
    };
    let wall_s = started.elapsed().as_secs_f64();
    let played_s = end["tick"].as_u64().unwrap() as f64 / 60.0;
    println!("{perceptions} perceptions, {played_s:.0} s of play in {wall_s:.2} s");
    assert_eq!(end["reason"], "finished");
    assert!(perceptions > 100, "{perceptions} perceptions");
    // In real time this would take as long as the play; at the bot's pace it takes a
    // small part of it, whatever the machine (a perception and its answer are some
    // hundreds of microseconds).
    assert!(
        played_s > 5.0 * wall_s,
        "{played_s:.0} s of play took {wall_s:.1} s"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lockstep_bot_answering_each_perception_once_is_never_rate_limited() {
    let (server, id, mut bot) = fast_lockstep_bot("lockstep-limits").await;
    let before = server.tick(&id);
    let (answers, errors, closed) = answer_every_perception(&mut bot, 0, 3).await;
    let ticks = server.tick(&id) - before;
    println!("{answers} answers, {ticks} ticks in 3 s at a limit of 20 messages a second");
    assert_eq!(
        closed, None,
        "closed after {answers} answers, errors {errors:?}"
    );
    assert!(!errors.contains(&"rate_limited".to_string()), "{errors:?}");
    // Far over the 20 a second the bucket allows: the answers are free.
    assert!(answers > 300, "only {answers} answers in 3 s");
    // The match goes as fast as the bot answers, not at the 5 ms deadline (200 Hz).
    assert!(ticks + 50 >= answers, "{ticks} ticks for {answers} answers");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lockstep_bot_sending_more_than_its_answers_is_still_limited() {
    let (_server, _id, mut bot) = fast_lockstep_bot("lockstep-greedy").await;
    let (answers, errors, closed) = answer_every_perception(&mut bot, 1, 3).await;
    assert!(
        errors.contains(&"rate_limited".to_string()) || closed == Some(1008),
        "{answers} answers with an extra message each, errors {errors:?}, close {closed:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn at_most_max_matches_ended_matches_are_kept_the_most_recent() {
    let server = with_settings(
        "two-ended",
        "max_matches = 2\nended_match_ttl_s = 600\n",
        &[],
    );
    let mut ids = Vec::new();
    for _ in 0..5 {
        let (id, _) =
            server.create(json!({"sport": "baseball", "mode": "fast", "duration_s": 0.5}));
        common::until(
            Duration::from_secs(10),
            &format!("{id} never ended"),
            || server.get(&format!("/api/matches/{id}"))["status"] == "ended",
        )
        .await;
        ids.push(id);
    }
    // The sweep runs at least once a second, and at every creation: wait for it to cut
    // the list down, then see which it kept.
    let list = || -> Vec<String> {
        server.get("/api/matches")["matches"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["id"].as_str().unwrap().to_string())
            .collect()
    };
    common::until(
        Duration::from_secs(3),
        "the sweep never cut the ended matches down to max_matches",
        || list().len() <= 2,
    )
    .await;
    let listed = list();
    let mut newest = ids[3..].to_vec();
    newest.sort();
    let mut kept = listed.clone();
    kept.sort();
    assert_eq!(kept, newest, "listed {listed:?} of {ids:?}");
}
