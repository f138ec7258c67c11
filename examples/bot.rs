//! A minimal fieldhouse bot: it plays one agent of a match over the WebSocket protocol
//! (PROTOCOL.md). Get a token by creating a match with `"bot": true` on an agent, then:
//!
//! ```text
//! cargo run --example bot -- ws://127.0.0.1:7878/ws/matches/ID/play TOKEN
//! ```

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use tokio_tungstenite::{connect_async, tungstenite::Message};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (Some(url), Some(token)) = (args.next(), args.next()) else {
        return Err("usage: bot ws://HOST:PORT/ws/matches/ID/play TOKEN".into());
    };
    // The token goes in the query (or an `Authorization: Bearer` header). A wrong token
    // or match id is refused (403, 404) before the WebSocket opens, with the reason as
    // JSON in the response's body.
    let (mut socket, _) = match connect_async(format!("{url}?token={token}")).await {
        Ok(connected) => connected,
        Err(tokio_tungstenite::tungstenite::Error::Http(response)) => {
            let body = response.body().as_deref().unwrap_or_default();
            let reason = String::from_utf8_lossy(body);
            return Err(format!("refused with {}: {reason}", response.status()).into());
        }
        Err(e) => return Err(e.into()),
    };
    // Every message is one JSON object in a text frame, tagged by its "type".
    while let Some(message) = socket.next().await {
        let Message::Text(text) = message? else {
            continue; // pings are answered by the library; the close frame ends the loop
        };
        let msg: Value = serde_json::from_str(&text)?;
        match msg["type"].as_str() {
            // Always first: the match (sport, tick_hz, perception_every_ticks, ...).
            Some("hello") => println!("playing {} in {}", msg["agent"], msg["match"]["sport"]),
            // Every perception_every_ticks ticks: answer with a command for that tick.
            Some("perception") => {
                let action = act(&msg["perception"]);
                let command = json!({"type": "command", "tick": msg["tick"], "action": action});
                socket.send(Message::text(command.to_string())).await?;
            }
            // About something we sent; the connection stays open.
            Some("error") => eprintln!("error {}: {}", msg["code"], msg["message"]),
            // The last message: the server closes the socket right after it (1000, or
            // 1001 if the server is shutting down).
            Some("end") => {
                println!("end ({}): {}", msg["reason"], msg["result"]);
                break;
            }
            _ => {} // ignore types this bot does not know
        }
    }
    Ok(())
}

/// Picks an action. Points are [x, z] in metres on the ground; angles are radians from
/// +x toward +z.
fn act(p: &Value) -> Value {
    let xz = |v: &Value| [v[0].as_f64().unwrap_or(0.0), v[1].as_f64().unwrap_or(0.0)];
    if let Some(optics) = p.get("optics") {
        // A fielder (baseball, cricket). Between balls nothing moves, and each launch puts
        // the fielder back home at rest: ask for home so it stays there until it sees the
        // new ball (an order holds until the next one).
        if optics.is_null() {
            return json!({"kind": "run_to", "target": p["self"]["home"]});
        }
        // In play: run to the ground point under the ball, which lies along the bearing
        // alpha at distance_m (the rates and tan_psi are there for smarter strategies).
        let me = xz(&p["self"]["position"]);
        let alpha = optics["alpha"].as_f64().unwrap_or(0.0);
        let d = optics["distance_m"].as_f64().unwrap_or(0.0);
        let target = [me[0] + d * alpha.cos(), me[1] + d * alpha.sin()];
        return json!({"kind": "run_to", "target": target});
    }
    // A basketball player: `self` is our id among `agents`.
    let basket = xz(&p["basket"]);
    let mine = p["agents"]
        .as_array()
        .and_then(|v| v.iter().find(|a| a["id"] == p["self"]));
    let me = mine.map_or(basket, |a| xz(&a["position"]));
    if p["has_ball"] == true {
        // With the ball: drive to the basket and shoot from within 5 m.
        if (me[0] - basket[0]).hypot(me[1] - basket[1]) <= 5.0 {
            return json!({"kind": "shoot"});
        }
        return json!({"kind": "move_to", "target": basket});
    }
    // Without it: wait for a pass 4 m out from the basket, on our side of the court.
    let side = if me[1] >= 0.0 { 2.5 } else { -2.5 };
    json!({"kind": "move_to", "target": [basket[0] + 4.0, side]})
}
