// What the 3-D view's browser scripts share: a free loopback port, the real server
// started on it, and Debian's chromium with software WebGL (the CI machine has no GPU).
import { chromium } from "playwright-core";
import { spawn } from "node:child_process";
import { createServer } from "node:net";

export const env = (name, fallback) => {
  const v = process.env[name] ?? fallback;
  if (v === undefined) throw new Error(`${name} is not set (tests/browser.rs sets it)`);
  return v;
};

export async function freePort() {
  return new Promise((resolve) => {
    const s = createServer().listen(0, "127.0.0.1", () => { const { port } = s.address(); s.close(() => resolve(port)); });
  });
}

/** Starts `bin serve` on `port` with `extra` arguments; resolves once it listens. */
export function startServer(bin, port, extra = []) {
  return new Promise((resolve, reject) => {
    const child = spawn(bin, ["serve", "--addr", `127.0.0.1:${port}`, ...extra], {
      env: { ...process.env, FIELDHOUSE_ADMIN_TOKEN: "browser-test-admin-token", FIELDHOUSE_LOG: "info" },
      stdio: ["ignore", "ignore", "pipe"],
    });
    let said = "";
    child.stderr.on("data", (chunk) => {
      said += chunk;
      if (said.includes("listening")) resolve(child);
    });
    child.on("exit", (code) => reject(new Error(`the server exited (${code}) before listening:\n${said}`)));
  });
}

/**
 * Headless chromium at `executablePath`, kept off the network, with WebGL drawn by
 * SwiftShader (software): what a machine without a GPU, like CI's, renders with.
 */
export function launch(executablePath) {
  return chromium.launch({
    executablePath,
    args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
      "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  });
}
