// The study page: shows what the server says and sends the stick. The robot's step runs on the
// server only (lasa.live.web.conversation); this page never computes a state. The robot is a JPEG frame from
// the server (--frames server) or drawn here from the tick's joint positions (--frames browser:
// view.js, MuJoCo's WebAssembly build and three.js, loaded on the server's first "scene" message).
"use strict";

const SEND_HZ = 20; // input messages a second while driving (the server allows 50)
const BEAT_MS = 1000; // the heartbeat: a "beat" every second, from this page's main thread, in every step
const MOMENT_MS = 2000; // how long "Done" or "Time is up" stays before the next step
const DEADZONE = 0.05;
const $ = (id) => document.getElementById(id);
// The token is in the link's fragment (#token=...), which the browser never sends: it travels once,
// as the WebSocket's first message, and never in a URL that a server or a proxy could log.
const token = new URLSearchParams(location.hash.slice(1)).get("token") || "";
const scheme = location.protocol === "https:" ? "wss" : "ws";
const RETRY_S = [1, 2, 3, 5, 5, 10]; // waits between reconnection attempts, then every 10 s
let ws = null, retries = 0;
let admitted = false; // whether the server has let this page in (then an "elsewhere" is a reload's race)
let racing = false; // this page's own older connection still held: try again
let leaving = false; // the page is being closed or reloaded: it must not connect again
for (const event of ["beforeunload", "pagehide"]) { // a reload starts: this page's connection is done
  window.addEventListener(event, () => { leaving = true; if (ws) ws.close(1000); });
}

// Why the server refused this page's connection (lasa.live.web.app.REFUSALS), in the participant's words.
const REFUSED = {
  invalid: "This link is not valid. Check that you opened the whole link you were sent, then try again.",
  finished: "You have finished the study with this link. Thank you! You may close this page.",
  elsewhere: "This link is open in another window or tab. Close that one, then reload this page.",
  replaced: "This study continues in another window or tab. You may close this one.",
  no_hello: "This page could not reach the study in time. Reload this page.",
};
let refused = false;
// How a connection ended, by its close code, when the page will try again by itself.
const LOST = {
  1012: "The study server is restarting. This page reconnects by itself; you will go on where you left off.",
  1001: "The study server is restarting. This page reconnects by itself; you will go on where you left off.",
};
const LOST_OTHER = "The connection to the study was lost. This page reconnects by itself; you will go on where you left off.";
const CLOSED = "The study server closed this page's connection. This page reconnects by itself; you will go on where you left off.";
const REPLACED = 4000; // lasa.live.web.conversation.REPLACED: a newer page of this link took over

const keys = { left: false, right: false, up: false, down: false };
let keyStop = false, modePress = false, driving = false, padWasPressed = false, frameUrl = null;
let view = null; // view.js once a "scene" message has come (--frames browser)
let lastTick = null; // the running trial's latest tick: how it ended (done, out of time)

function show(id) {
  for (const s of document.querySelectorAll("section")) s.hidden = s.id !== id;
}

function send(msg) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}

// A duration as a person reads it: "45 seconds", "1 minute", "5 minutes", "about 1.5 hours".
function duration(seconds) {
  if (seconds < 90) return `${Math.round(seconds)} seconds`;
  const minutes = Math.round(seconds / 60);
  if (minutes < 90) return minutes === 1 ? "1 minute" : `${minutes} minutes`;
  const hours = Math.round(minutes / 30) / 2;
  return hours === 1 ? "about an hour" : `about ${hours} hours`;
}

// Whether this browser can draw the robot (--frames browser): a WebGL context, asked before consent.
function webgl() {
  try {
    const canvas = document.createElement("canvas");
    return !!(canvas.getContext("webgl2") || canvas.getContext("webgl"));
  } catch (err) {
    return false;
  }
}
const NO_WEBGL = "This browser cannot run the study: it cannot draw the robot (it has no WebGL). Please open "
  + "your link in an up-to-date Chrome, Firefox, Edge or Safari, with hardware acceleration turned on in its "
  + "settings, on a computer rather than a phone.";

// The consent text: the server's HTML of the study's Markdown (raw HTML in it is shown as text).
function consent(msg) {
  if (msg.webgl && !webgl()) {
    refused = true; // nothing this page can do: no consent, no reconnection
    $("status").textContent = "";
    $("error-text").textContent = NO_WEBGL;
    return show("error");
  }
  $("consent-text").innerHTML = msg.html;
  show("consent");
}

// The optional questions about the participant, once, before the first practice.
function demographics(msg) {
  const form = $("demographics-form");
  form.replaceChildren(...msg.items.map((item) => {
    const div = Object.assign(document.createElement("div"), { className: "question" });
    div.dataset.item = item.item;
    div.append(Object.assign(document.createElement("p"), { textContent: item.question }));
    for (const answer of item.answers) {
      const label = document.createElement("label");
      const input = Object.assign(document.createElement("input"), { type: "radio", name: item.item, value: answer });
      label.append(input, ` ${answer}`);
      div.append(label);
    }
    return div;
  }));
  show("demographics");
}

// The stick check before the first practice: each of the four directions, shown as it is reached.
const reached = new Set();
let checking = false;
function startCheck() {
  reached.clear();
  for (const span of document.querySelectorAll("#check [data-dir]")) span.classList.remove("reached");
  checking = true;
  $("check").hidden = false;
  $("start").disabled = true;
}
setInterval(() => {
  if ($("intro").hidden) return;
  if (!checking) { gamepad(); return; } // a pad plugged in now: said at once if it cannot be used
  const [x, y] = stick().axes;
  const now = { left: x < -0.5, right: x > 0.5, up: y > 0.5, down: y < -0.5 };
  for (const dir in now) {
    if (!now[dir]) continue;
    reached.add(dir);
    document.querySelector(`#check [data-dir="${dir}"]`).classList.add("reached");
  }
  if (reached.size === 4) { checking = false; $("start").disabled = false; }
}, 50);

function phase(msg) {
  driving = false;
  const ended = lastTick && !$("drive").hidden && (lastTick.done ? "Done" : lastTick.remaining_s <= 0 ? "Time is up" : "");
  lastTick = null;
  if (ended) { // a moment to see the trial end before the next step
    $("instruction").textContent = ended;
    setTimeout(() => phase(msg), MOMENT_MS);
    return;
  }
  notice(""); // a new step: a form's message belongs to the step before
  $("status").textContent = msg.index ? `Step ${msg.index} of ${msg.total}` : "";
  if (msg.kind === "consent") return consent(msg);
  if (msg.kind === "demographics") return demographics(msg);
  if (msg.kind === "thanks") return thanks(msg);
  if (msg.kind === "survey") return survey(msg);
  const practice = msg.kind === "practice";
  // the condition's letter in this participant's order, never its code (a blind protocol)
  $("intro-title").textContent = practice ? `Practice: way ${msg.label}` : `${msg.task}: way ${msg.label}`;
  $("intro-text").textContent = practice
    ? `Get to know way ${msg.label} of controlling the robot, for up to ${duration(msg.limit_s)}. End the practice when you are ready.`
    : `Feed the ${msg.task.toLowerCase()} following the instruction at the top of the screen (at most ${duration(msg.limit_s)}).`;
  $("ready").hidden = !practice;
  checking = false;
  $("check").hidden = true;
  $("start").disabled = false;
  if (practice && msg.index === 1) startCheck();
  show("intro");
  if (msg.resume) startDriving(); // the page left this trial (a reload, a lost network): on again by itself
}

// The thank-you page: the participant's id (for a withdrawal), the recruiter's completion code and link.
function thanks(msg) {
  $("participant").textContent = msg.participant || "";
  $("completion-code").textContent = msg.code || "";
  $("completion").hidden = !msg.code;
  if (msg.url) $("completion-url").href = msg.url;
  $("completion-link").hidden = !msg.url;
  show("thanks");
}

// One question of radio buttons: values, each labelled, with the words at its two ends.
function scale(name, text, values, low, high, className) {
  const div = Object.assign(document.createElement("div"), { className: `question ${className}` });
  div.dataset.name = name;
  div.append(Object.assign(document.createElement("p"), { textContent: text }));
  const points = Object.assign(document.createElement("div"), { className: "points" });
  for (const v of values) {
    const label = Object.assign(document.createElement("label"), { title: `${v}` });
    label.append(Object.assign(document.createElement("input"), { type: "radio", name, value: v }));
    if (className === "likert") label.append(` ${v}`);
    points.append(label);
  }
  div.append(points);
  const ends = Object.assign(document.createElement("div"), { className: "ends" });
  ends.append(Object.assign(document.createElement("span"), { textContent: low }),
    Object.assign(document.createElement("span"), { textContent: high }));
  div.append(ends);
  return div;
}

function survey(msg) {
  $("survey-title").textContent = `About way ${msg.label}, which you just used`;
  const [low, high] = msg.likert_anchors;
  $("likert-anchors").textContent = `1 = ${low} … 7 = ${high}`;
  $("likert").replaceChildren(...msg.questions.map((q) =>
    scale(q.scale, q.text, [1, 2, 3, 4, 5, 6, 7], `1 = ${low}`, `7 = ${high}`, "likert")));
  const tlxValues = [];
  for (let v = 0; v <= 100; v += msg.tlx_step) tlxValues.push(v);
  $("tlx").replaceChildren(...msg.tlx.map((q) => scale(`tlx-${q.name}`, q.question, tlxValues, q.low, q.high, "tlx")));
  $("comment").value = "";
  $("comment").maxLength = msg.comment_chars;
  show("survey");
}

// Seconds as the time left reads: "4:05".
function clock(seconds) {
  const s = Math.max(0, Math.ceil(seconds));
  return `${Math.floor(s / 60)}:${String(s % 60).padStart(2, "0")}`;
}

function tick(msg) {
  lastTick = msg;
  $("drive").dataset.tick = msg.step; // for tests only: the page shows no counter
  $("instruction").textContent = msg.instruction;
  $("left").textContent = `${clock(msg.remaining_s)} left`;
  $("stopped").hidden = !msg.stop;
  $("belief-panel").hidden = !msg.belief; // only when the study shows it (off by default)
  if (!msg.belief) return;
  const belief = $("belief");
  if (belief.children.length !== msg.goals.length) {
    belief.replaceChildren(...msg.goals.map((g) => {
      const row = document.createElement("div");
      row.className = "goal";
      row.innerHTML = '<span class="name"></span><span class="track"><div class="bar"></div></span><span class="value"></span>';
      row.querySelector(".name").textContent = g;
      return row;
    }));
  }
  msg.belief.forEach((p, i) => {
    const row = belief.children[i];
    row.querySelector(".bar").style.width = `${(100 * p).toFixed(1)}%`;
    row.querySelector(".value").textContent = p.toFixed(2);
  });
}

// The goals' names over the picture, where the server's camera sees each goal (lasa.live.web.app.goal_labels).
function labels(msg) {
  $("labels").replaceChildren(...msg.labels.map((g) => {
    const span = Object.assign(document.createElement("span"), { textContent: g.name });
    span.style.left = `${(100 * g.x).toFixed(2)}%`;
    span.style.top = `${(100 * g.y).toFixed(2)}%`;
    return span;
  }));
}

// The trial's scene (--frames browser): loaded, drawn at its start pose, then "ready" (the clock starts).
function scene(msg) {
  $("view").hidden = true;
  $("canvas").hidden = false;
  view = import("/static/view.js");
  view.then((m) => m.load(msg.key, msg, $("canvas")).then(() => m.show(msg.q)))
    .then(() => requestAnimationFrame(() => requestAnimationFrame(() => send({ type: "ready" }))))
    .catch(() => {
      $("status").textContent = "The robot cannot be drawn in this browser; the task goes on.";
      send({ type: "ready" });
    });
}

function frame(blob) {
  if (frameUrl) URL.revokeObjectURL(frameUrl);
  frameUrl = URL.createObjectURL(blob);
  $("view").src = frameUrl;
}

function stick() {
  let x = (keys.right ? 1 : 0) - (keys.left ? 1 : 0);
  let y = (keys.up ? 1 : 0) - (keys.down ? 1 : 0);
  let stop = keyStop, mode = modePress;
  const pad = gamepad();
  if (pad) {
    const ax = pad.axes[0] || 0, ay = -(pad.axes[1] || 0);
    if (Math.abs(ax) >= DEADZONE) x = ax;
    if (Math.abs(ay) >= DEADZONE) y = ay;
    const pressed = !!(pad.buttons[0] && pad.buttons[0].pressed);
    mode = mode || (pressed && !padWasPressed);
    padWasPressed = pressed;
    stop = stop || !!(pad.buttons[1] && pad.buttons[1].pressed);
  }
  modePress = false;
  return { type: "input", axes: [x, y], mode, stop };
}

// The gamepad in use: a connected one the browser reads in the standard layout (any other is not used,
// and the page says so).
function gamepad() {
  const pads = navigator.getGamepads ? [...navigator.getGamepads()].filter((p) => p && p.connected) : [];
  const pad = pads.find((p) => p.mapping === "standard") || null;
  $("pad-notice").hidden = !(pads.length && !pad);
  return pad;
}

// What the session records of the device in use: the keyboard, or the gamepad's name and layout.
function device() {
  const pad = gamepad();
  return pad ? { kind: "gamepad", id: pad.id.slice(0, 100), mapping: pad.mapping } : { kind: "keyboard" };
}

setInterval(() => {
  if (driving) send(stick());
}, 1000 / SEND_HZ);
setInterval(() => send({ type: "beat" }), BEAT_MS); // a frozen tab sends none: the server notes it

const KEYS = { ArrowLeft: "left", ArrowRight: "right", ArrowUp: "up", ArrowDown: "down" };
document.addEventListener("keydown", (e) => {
  if (!driving && !checking) return;
  if (KEYS[e.key]) keys[KEYS[e.key]] = true;
  else if (e.key === "m" || e.key === "M") modePress = true;
  else if ((e.key === "s" || e.key === "S" || e.key === " ") && !e.repeat) keyStop = !keyStop;
  else return;
  e.preventDefault();
});
document.addEventListener("keyup", (e) => {
  if (KEYS[e.key]) keys[KEYS[e.key]] = false;
});
window.addEventListener("blur", () => { for (const k in keys) keys[k] = false; });

$("agree").onclick = () => send({ type: "consent" });
function startDriving() {
  for (const k in keys) keys[k] = false;
  keyStop = false;
  driving = true;
  checking = false;
  lastTick = null;
  $("instruction").textContent = "Loading the robot…"; // the clock starts once the picture is there
  $("left").textContent = "";
  show("drive");
  send({ type: "start", device: device() });
}
$("start").onclick = startDriving;
$("ready").onclick = () => send({ type: "finish" });
$("submit").onclick = () => {
  const chosen = (q) => { const c = q.querySelector("input:checked"); return c ? Number(c.value) : null; };
  const answers = [...document.querySelectorAll("#likert .question")].map(chosen);
  const tlx = [...document.querySelectorAll("#tlx .question")].map(chosen);
  if (answers.includes(null) || tlx.includes(null)) { notice("Please answer every question (the comment is optional)."); return; }
  notice("");
  send({ type: "survey", answers, tlx, comment: $("comment").value });
};
$("demographics-submit").onclick = () => {
  const answers = {};
  for (const q of document.querySelectorAll("#demographics-form .question")) {
    const c = q.querySelector("input:checked");
    if (c) answers[q.dataset.item] = c.value;
  }
  send({ type: "demographics", answers });
};
$("demographics-skip").onclick = () => send({ type: "demographics", skip: true });

function received(event) {
  if (typeof event.data !== "string") return frame(event.data);
  const msg = JSON.parse(event.data);
  if (msg.type === "phase") phase(msg);
  else if (msg.type === "tick") { tick(msg); if (view) view.then((m) => m.show(msg.q)); }
  else if (msg.type === "scene") scene(msg);
  else if (msg.type === "labels") labels(msg);
  else if (msg.type === "error") notice(msg.message); // the page stays as it is: a form keeps its answers
  else if (msg.type === "refused") {
    // a page the server had let in, refused as "elsewhere": its own earlier connection not yet let go
    if (msg.reason === "elsewhere" && admitted) { racing = true; return; }
    stop(msg.reason);
  }
}

// The server sent this page away for good: say why (REFUSED) and stop trying.
function stop(reason) {
  refused = true;
  driving = false;
  notice("");
  $("status").textContent = "";
  $("error-text").textContent = REFUSED[reason] || REFUSED.invalid;
  show("error");
}

// A message above the page's current step, which it never replaces ("" clears it).
function notice(text) {
  $("notice").textContent = text;
  $("notice").hidden = !text;
}

function connect() {
  ws = new WebSocket(`${scheme}://${location.host}/ws`);
  ws.binaryType = "blob";
  ws.onopen = () => { ws.send(JSON.stringify({ type: "hello", token })); };
  ws.onmessage = (event) => {
    const refusal = typeof event.data === "string" && event.data.includes('"refused"');
    if (!refusal) admitted = true;
    if (retries && !refusal) { retries = 0; notice(""); } // the server answered: back where we left off
    received(event);
  };
  ws.onclose = (event) => {
    driving = false;
    if (leaving) return; // a reload's new page connects itself
    if (event.code === REPLACED) return stop("replaced"); // a newer page of this link drives: this one stops
    if (!$("thanks").hidden || refused || event.code === 1000) return;
    // a refused message (1008, 1009: too many, too large); a retry that finds no server yet keeps
    // the notice of why the connection ended ("restarting")
    const message = racing ? LOST_OTHER : event.code === 1008 || event.code === 1009
      ? CLOSED
      : LOST[event.code] || (retries ? $("notice").textContent : LOST_OTHER);
    racing = false;
    notice(message || LOST_OTHER);
    setTimeout(connect, 1000 * RETRY_S[Math.min(retries, RETRY_S.length - 1)]);
    retries += 1;
  };
}
connect();
