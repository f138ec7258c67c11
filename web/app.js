// The spectator page's entry: a hash router. `#/` is the lobby, `#/matches/ID` a live
// match and `#/replays/ID` a replay, so every view can be shared, bookmarked and
// reloaded. The server speaks the protocol in PROTOCOL.md; nothing here is built.
import { showLobby } from "./lobby.js";
import { showView } from "./view.js";

let close = null;

function route() {
  if (close) close();
  const m = location.hash.match(/^#\/(matches|replays)\/([\w-]+)$/);
  close = m ? showView(m[1], decodeURIComponent(m[2])) : showLobby();
}

window.addEventListener("hashchange", route);
route();
