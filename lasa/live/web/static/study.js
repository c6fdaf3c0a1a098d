// The study page: shows what the server says and sends the stick. The robot's step runs on the
// server only (lasa.live.web.conversation); this page never computes a state. The robot is a JPEG frame from
// the server (--frames server) or drawn here from the tick's joint positions (--frames browser:
// view.js, MuJoCo's WebAssembly build and three.js, loaded on the server's first "scene" message).
"use strict";

const SEND_HZ = 20; // input messages a second while driving (the server allows 50)
const DEADZONE = 0.05;
const $ = (id) => document.getElementById(id);
// The token is in the link's fragment (#token=...), which the browser never sends: it travels once,
// as the WebSocket's first message, and never in a URL that a server or a proxy could log.
const token = new URLSearchParams(location.hash.slice(1)).get("token") || "";
const scheme = location.protocol === "https:" ? "wss" : "ws";
const RETRY_S = [1, 2, 3, 5, 5, 10]; // waits between reconnection attempts, then every 10 s
let ws = null, retries = 0;

// Why the server refused this page's connection (lasa.live.web.app.REFUSALS), in the participant's words.
const REFUSED = {
  invalid: "This link is not valid. Check that you opened the whole link you were sent, then try again.",
  finished: "You have finished the study with this link. Thank you! You may close this page.",
  elsewhere: "This link is open in another window or tab. Close that one, then reload this page.",
  no_hello: "This page could not reach the study in time. Reload this page.",
};
let refused = false;
// How a connection ended, by its close code, when the page will try again by itself.
const LOST = {
  1012: "The study server is restarting. This page reconnects by itself; you will go on where you left off.",
  1001: "The study server is restarting. This page reconnects by itself; you will go on where you left off.",
};
const LOST_OTHER = "The connection to the study was lost. This page reconnects by itself; you will go on where you left off.";

const keys = { left: false, right: false, up: false, down: false };
let keyStop = false, modePress = false, driving = false, padWasPressed = false, frameUrl = null;
let view = null; // view.js once a "scene" message has come (--frames browser)

function show(id) {
  for (const s of document.querySelectorAll("section")) s.hidden = s.id !== id;
}

function send(msg) {
  if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}

// A duration as a person reads it: "45 seconds", "1 minute", "5 minutes", "about 1.5 hours".
function duration(seconds) {
  if (seconds < 90) return `${Math.round(seconds)} seconds`;
  const minutes = Math.round(seconds / 60);
  if (minutes < 90) return minutes === 1 ? "1 minute" : `${minutes} minutes`;
  const hours = Math.round(minutes / 30) / 2;
  return hours === 1 ? "about an hour" : `about ${hours} hours`;
}

function consent(msg) {
  $("consent-conditions").textContent = ["no", "one", "two", "three", "four", "five", "six"][msg.conditions] || msg.conditions;
  $("consent-practice").textContent = duration(msg.practice_s);
  $("consent-trial").textContent = duration(msg.trial_s);
  $("consent-total").textContent = duration(60 * msg.longest_min);
  show("consent");
}

function phase(msg) {
  driving = false;
  $("status").textContent = msg.index ? `Step ${msg.index} of ${msg.total}` : "";
  if (msg.kind === "consent") return consent(msg);
  if (msg.kind === "thanks") return show(msg.kind);
  if (msg.kind === "survey") return survey(msg);
  const practice = msg.kind === "practice";
  // the condition's letter in this participant's order, never its code (a blind protocol)
  $("intro-title").textContent = practice ? `Practice: way ${msg.label}` : `${msg.task}: way ${msg.label}`;
  $("intro-text").textContent = practice
    ? `Get to know way ${msg.label} of controlling the robot, for up to ${duration(msg.limit_s)}. End the practice when you are ready.`
    : `Feed the ${msg.task.toLowerCase()} following the instruction at the top of the screen (at most ${duration(msg.limit_s)}).`;
  $("ready").hidden = !practice;
  show("intro");
}

function survey(msg) {
  $("survey-title").textContent = `About way ${msg.label}, which you just used`;
  const form = $("survey-form");
  form.replaceChildren();
  for (const q of msg.questions) {
    const div = document.createElement("div");
    div.className = "question";
    div.append(Object.assign(document.createElement("p"), { textContent: q.text }));
    for (let v = 1; v <= 7; v++) {
      const label = document.createElement("label");
      const input = Object.assign(document.createElement("input"), { type: "radio", name: q.scale, value: v });
      label.append(input, ` ${v}`);
      div.append(label);
    }
    form.append(div);
  }
  show("survey");
}

function tick(msg) {
  $("instruction").textContent = msg.instruction;
  $("tick").textContent = msg.step;
  $("late").textContent = msg.late;
  $("left").textContent = msg.remaining_s.toFixed(0);
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

function scene(msg) {
  $("view").hidden = true;
  $("canvas").hidden = false;
  view = import("/static/view.js");
  view.then((m) => m.load(msg.key, msg, $("canvas"))).catch((err) => {
    $("status").textContent = `The robot cannot be drawn in this browser (${err.message || err}); the task goes on.`;
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
  const pad = navigator.getGamepads ? [...navigator.getGamepads()].find((p) => p && p.connected) : null;
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

setInterval(() => {
  if (!driving) return;
  const msg = stick();
  $("stick").textContent = `${msg.axes[0].toFixed(2)}, ${msg.axes[1].toFixed(2)}`;
  send(msg);
}, 1000 / SEND_HZ);

const KEYS = { ArrowLeft: "left", ArrowRight: "right", ArrowUp: "up", ArrowDown: "down" };
document.addEventListener("keydown", (e) => {
  if (!driving) return;
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
$("start").onclick = () => {
  for (const k in keys) keys[k] = false;
  keyStop = false;
  driving = true;
  $("instruction").textContent = "Starting…";
  show("drive");
  send({ type: "start" });
};
$("ready").onclick = () => send({ type: "finish" });
$("submit").onclick = () => {
  const answers = [...$("survey-form").querySelectorAll(".question")].map((q) => {
    const checked = q.querySelector("input:checked");
    return checked ? Number(checked.value) : 0;
  });
  if (answers.includes(0)) { alert("Please answer every question."); return; }
  send({ type: "survey", answers });
};

function received(event) {
  if (typeof event.data !== "string") return frame(event.data);
  const msg = JSON.parse(event.data);
  if (msg.type === "phase") phase(msg);
  else if (msg.type === "tick") { tick(msg); if (view) view.then((m) => m.show(msg.q)); }
  else if (msg.type === "scene") scene(msg);
  else if (msg.type === "labels") labels(msg);
  else if (msg.type === "error") notice(msg.message); // the page stays as it is: a form keeps its answers
  else if (msg.type === "refused") {
    refused = true;
    notice("");
    $("status").textContent = "";
    $("error-text").textContent = REFUSED[msg.reason] || REFUSED.invalid;
    show("error");
  }
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
    if (retries) { retries = 0; notice(""); } // the server answered: back where we left off
    received(event);
  };
  ws.onclose = (event) => {
    driving = false;
    if (!$("thanks").hidden || refused || event.code === 1000) return;
    // a refused message (1008: too many, not the protocol's; 1009: too large) names its reason
    const refusedMessage = (event.code === 1008 || event.code === 1009) && event.reason;
    // a retry that finds no server yet keeps the notice of why the connection ended ("restarting")
    const message = refusedMessage
      ? `The study server closed this page's connection: ${event.reason}. This page reconnects by itself; you will go on where you left off.`
      : LOST[event.code] || (retries ? $("notice").textContent : LOST_OTHER);
    notice(message || LOST_OTHER);
    setTimeout(connect, 1000 * RETRY_S[Math.min(retries, RETRY_S.length - 1)]);
    retries += 1;
  };
}
connect();
