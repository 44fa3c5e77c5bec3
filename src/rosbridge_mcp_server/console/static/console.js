// The operator console: one event stream in, a few kinds of request out (approve, deny, stop, release, the
// camera's topic, the map panel's topic and base frame). The secret comes in the URL's fragment once, and is then kept for this tab only.
"use strict";

const SECRET_HEADER = "X-Console-Secret";
const TOKEN_HEADER = "X-Confirmation-Token";
// A link from the MCP client (URL-mode elicitation) names one confirmation and carries its own token: it can
// answer that confirmation and nothing else. Read before the fragment leaves the address bar.
const link = (() => {
  const match = location.hash.match(/confirm=(c\d+)&token=([A-Za-z0-9_-]+)/);
  return match ? { id: match[1], token: match[2] } : null;
})();
if (link && !location.hash.includes("secret=")) history.replaceState(null, "", location.pathname);
const secret = (() => {
  const match = location.hash.match(/secret=([A-Za-z0-9_-]+)/);
  if (match) {
    sessionStorage.setItem("consoleSecret", match[1]);
    history.replaceState(null, "", location.pathname);
  }
  return sessionStorage.getItem("consoleSecret") || "";
})();

const $ = (id) => document.getElementById(id);

// Every time on the page in one form: 24-hour local time, HH:MM:SS (the server's down_since is written so too).
function clock(date) {
  const two = (n) => String(n).padStart(2, "0");
  return `${two(date.getHours())}:${two(date.getMinutes())}:${two(date.getSeconds())}`;
}

function el(tag, text, className) {
  const node = document.createElement(tag);
  if (text !== undefined && text !== null) node.textContent = String(text);
  if (className) node.className = className;
  return node;
}

function problem(text) {
  $("problem").textContent = text || "";
  $("problem").hidden = !text;
}

async function post(path, body) {
  try {
    const response = await fetch(path, {
      method: "POST",
      headers: { [SECRET_HEADER]: secret, "Content-Type": "application/json" },
      body: JSON.stringify(body || {}),
    });
    const answer = await response.json().catch(() => ({}));
    problem(response.ok ? "" : answer.error || `${path}: HTTP ${response.status}`);
    return answer;
  } catch (error) {
    problem(`The console server did not answer: ${error}`);
    return {};
  }
}

function renderRobots(robots) {
  const list = $("robots");
  list.replaceChildren();
  for (const robot of robots) {
    const item = el("li");
    item.dataset.robot = robot.name;
    item.append(el("strong", robot.name), " ");
    const down = robot.down_since ? `not connected since ${robot.down_since}` : "not connected";
    item.append(el("span", robot.connected ? "connected" : down, robot.connected ? "ok" : "bad"));
    if (robot.ros) item.append(" · ", el("span", robot.ros, "ros"));
    item.append(el("div", robot.url, "mono"));
    list.append(item);
  }
}

function renderPending(pending) {
  const list = $("pending");
  list.replaceChildren();
  $("pending-empty").hidden = pending.length > 0;
  for (const entry of pending) {
    const item = el("li");
    item.dataset.id = entry.id;
    item.append(el("strong", `${entry.tool} → ${entry.name}`));
    if (entry.by_link) item.append(" ", el("small", "(your assistant's app also sent you a link to it)"));
    item.append(el("div", entry.question, "question"));
    const approve = el("button", "Approve", "approve");
    approve.type = "button";
    approve.addEventListener("click", () => post(`/api/confirmations/${entry.id}/approve`));
    const deny = el("button", "Deny", "deny");
    deny.type = "button";
    deny.addEventListener("click", () => post(`/api/confirmations/${entry.id}/deny`));
    item.append(approve, " ", deny);
    list.append(item);
  }
}

function renderRunning(robots, tasks) {
  const list = $("running");
  list.replaceChildren();
  let count = 0;
  for (const task of tasks || []) {
    count += 1;
    const item = el("li");
    item.dataset.task = task.id;
    item.append(el("strong", "task "), el("span", task.tool, "mono"), ` ${task.status}, ${task.seconds} s`);
    if (task.caller) item.append(` (${task.caller})`);
    if (task.message) item.append(el("div", task.message, "mono"));
    list.append(item);
  }
  for (const robot of robots) {
    for (const stream of robot.streams) {
      count += 1;
      const item = el("li");
      item.dataset.stream = stream.topic;
      item.append(el("strong", "stream "), el("span", stream.topic, "mono"), ` ${stream.type}`);
      if (stream.stopping) item.append(el("span", " stopping", "bad"));
      list.append(item);
    }
    for (const goal of robot.goals) {
      count += 1;
      const item = el("li");
      item.dataset.goal = goal.goal_id;
      item.append(el("strong", "goal "), el("span", goal.action, "mono"));
      item.append(` ${goal.seconds} s, ${goal.feedback_count} feedback`);
      if (goal.last_feedback) item.append(el("div", goal.last_feedback, "mono"));
      list.append(item);
    }
  }
  $("running-empty").hidden = count > 0;
}

function renderAudit(entries) {
  const list = $("audit");
  list.replaceChildren();
  $("audit-empty").hidden = entries.length > 0;
  for (const entry of entries) {
    const item = el("li");
    const outcome = String(entry.outcome || "");
    // "e-stop released" is good news: not in the red of refusals and of the e-stop itself.
    const kind = outcome.startsWith("e-stop released") ? "released" : outcome.split(/[: ]/)[0];
    item.append(el("span", outcome, `outcome ${kind}`), " ");
    if (entry.time) item.append(el("span", clock(new Date(entry.time)), "mono time"), " ");
    if (entry.robot) item.append(el("span", `[${entry.robot}] `));
    item.append(el("strong", entry.tool), " ", el("span", entry.name || "", "mono"), " ");
    if (entry.caller) item.append(el("span", `(by ${entry.caller}) `));
    if (entry.type) item.append(el("span", entry.type));
    if (entry.rate_hz) item.append(` at ${entry.rate_hz} Hz` + (entry.duration ? ` for ${entry.duration} s` : ""));
    if (entry.detail) item.append(el("div", entry.detail));
    if (entry.payload) item.append(el("div", entry.payload, "mono"));
    list.append(item);
  }
}

function renderState(state) {
  renderRobots(state.robots);
  renderPending(state.pending);
  renderRunning(state.robots, state.tasks);
  renderAudit(state.audit);
  const latched = state.estop.latched;
  $("latched").hidden = !latched;
  if (!latched) $("stopped").hidden = true;
  $("release").hidden = !latched;
  document.body.classList.toggle("is-latched", latched);
  const camera = state.camera;
  $("camera-status").dataset.topic = camera.topic || "";
  $("camera-status").textContent = camera.topic ? `${camera.topic}: ${camera.status}` : "off";
  if (!camera.topic) $("camera").hidden = true;
  renderMapState(state.map);
  renderStale(state.stale_since);
}

// While the robot is not connected, the last pose, map and frame stay, marked stale over the picture.
let staleSince = null;
function renderStale(since) {
  staleSince = since || null;
  const text = staleSince ? `stale since ${staleSince}` : "";
  for (const name of ["camera", "map"]) {
    $(`${name}-stale`).textContent = text;
    $(`${name}-stale`).hidden = !staleSince || $(name).hidden;
    $(`${name}-picture`).classList.toggle("is-stale", Boolean(staleSince));
  }
  $("pose").classList.toggle("is-stale", Boolean(staleSince));
  $("map-status").hidden = Boolean(staleSince);
  const cameraTopic = $("camera-status").dataset.topic;
  if (staleSince && cameraTopic) $("camera-status").textContent = `${cameraTopic}: stale, the last frame`;
  showPose();
}

function renderMapState(panel) {
  if (!panel) return;
  const topic = $("map-topic");
  const base = $("map-base");
  if (document.activeElement !== topic && document.activeElement !== base) {
    topic.value = panel.topic;
    base.value = panel.base_frame;
  }
  $("map-status").textContent = panel.map_status;
  $("pose").dataset.status = panel.status;
  showPose();
}

let lastPose = null;
function renderPose({ pose }) {
  const shown = $("pose");
  lastPose = pose;
  if (!pose) {
    delete shown.dataset.x;
  } else {
    shown.dataset.x = pose.x;
    shown.dataset.y = pose.y;
    shown.dataset.yaw = pose.yaw;
    shown.dataset.frame = pose.frame;
  }
  showPose();
}

// The pose line: the last pose (marked stale while the robot is away), else why there is none.
function showPose() {
  const shown = $("pose");
  const status = shown.dataset.status || "";
  if (lastPose && (status === "live" || staleSince)) {
    const parts = [
      `${lastPose.base_frame} in ${lastPose.frame}:`,
      `x ${lastPose.x.toFixed(2)} m,`,
      `y ${lastPose.y.toFixed(2)} m,`,
      `yaw ${lastPose.yaw.toFixed(1)}°`,
    ];
    if (staleSince) parts.push(`(stale since ${staleSince})`);
    shown.replaceChildren(...parts.flatMap((part, index) => (index ? [" ", el("span", part)] : [el("span", part)])));
  } else {
    shown.textContent = staleSince ? `stale since ${staleSince}: ${status || "no pose yet"}` : status || "no pose yet";
  }
}

function renderMap({ image }) {
  const shown = $("map");
  if (!image) {
    shown.hidden = true;
    shown.removeAttribute("src");
    return;
  }
  shown.src = image.src;
  shown.dataset.seq = image.seq;
  shown.width = image.width;
  shown.height = image.height;
  shown.hidden = false;
  renderStale(staleSince);
}

function renderFrame(frame) {
  const image = $("camera");
  image.src = frame.src;
  image.dataset.seq = frame.seq;
  image.dataset.topic = frame.topic;
  image.width = frame.width;
  image.height = frame.height;
  image.hidden = false;
  renderStale(staleSince);
}

// Server-sent events read through fetch, so the secret travels in a header (EventSource cannot send one).
async function listen() {
  for (;;) {
    try {
      const response = await fetch("/api/events", { headers: { [SECRET_HEADER]: secret } });
      if (!response.ok) {
        const answer = await response.json().catch(() => ({}));
        throw new Error(answer.error || `HTTP ${response.status}`);
      }
      $("link").textContent = "live";
      $("link").classList.remove("off");
      problem("");
      const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
      let buffer = "";
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buffer += value;
        let end;
        while ((end = buffer.indexOf("\n\n")) >= 0) {
          const block = buffer.slice(0, end);
          buffer = buffer.slice(end + 2);
          let name = "message";
          let data = "";
          for (const line of block.split("\n")) {
            if (line.startsWith("event: ")) name = line.slice(7);
            else if (line.startsWith("data: ")) data += line.slice(6);
          }
          if (!data) continue;
          if (name === "state") renderState(JSON.parse(data));
          else if (name === "frame") renderFrame(JSON.parse(data));
          else if (name === "pose") renderPose(JSON.parse(data));
          else if (name === "map") renderMap(JSON.parse(data));
        }
      }
      throw new Error("the console server closed the stream");
    } catch (error) {
      $("link").textContent = "not connected";
      $("link").classList.add("off");
      problem(`Not connected to the console server: ${error.message}. Trying again…`);
      await new Promise((resolve) => setTimeout(resolve, 1000));
    }
  }
}

async function loadImageTopics() {
  try {
    const response = await fetch("/api/image-topics", { headers: { [SECRET_HEADER]: secret } });
    if (!response.ok) return;
    const answer = await response.json();
    const topics = answer.topics;
    $("camera-topics").replaceChildren(...topics.map((topic) => { const o = el("option"); o.value = topic; return o; }));
    // The server's pick: the colour camera when there is one (not a depth or infrared image).
    if (!$("camera-topic").value && topics.length) $("camera-topic").value = answer.default || topics[0];
  } catch (error) { /* the picker stays empty; typing a topic still works */ }
}

async function showLink() {
  $("link-section").hidden = false;
  const headers = { [TOKEN_HEADER]: link.token };
  const say = (text) => { $("link-status").textContent = text; };
  try {
    const response = await fetch(`/api/confirmations/${link.id}`, { headers });
    const answer = await response.json().catch(() => ({}));
    if (!response.ok) {
      $("link-buttons").hidden = true;
      say(answer.error || `HTTP ${response.status}`);
      return;
    }
    $("link-question").textContent = answer.question;
  } catch (error) {
    say(`The console server did not answer: ${error}`);
    return;
  }
  const decide = async (verdict) => {
    const response = await fetch(`/api/confirmations/${link.id}/${verdict}`, {
      method: "POST",
      headers: { ...headers, "Content-Type": "application/json" },
      body: "{}",
    });
    const answer = await response.json().catch(() => ({}));
    $("link-buttons").hidden = true;
    say(response.ok ? `${answer.answer === "approved" ? "Approved" : "Denied"}. You can close this tab.` : answer.error || `HTTP ${response.status}`);
  };
  $("link-approve").addEventListener("click", () => decide("approve"));
  $("link-deny").addEventListener("click", () => decide("deny"));
}


// E-STOP answers with what it stopped; that (or its failure) stays on the page until the next press, so a
// press is never silent. It works without the secret too, from any tab of the console's own origin.
async function estop() {
  const shown = $("stopped");
  shown.classList.remove("failed");
  shown.textContent = "E-STOP: stopping…";
  shown.hidden = false;
  let answer = {};
  let failure = "";
  try {
    const response = await fetch("/api/estop", {
      method: "POST",
      headers: { [SECRET_HEADER]: secret, "Content-Type": "application/json" },
      body: "{}",
    });
    answer = await response.json().catch(() => ({}));
    if (!response.ok) failure = answer.error || `HTTP ${response.status}`;
  } catch (error) {
    failure = `the console server did not answer (${error})`;
  }
  const time = clock(new Date());
  shown.hidden = false;
  if (failure) {
    shown.classList.add("failed");
    shown.textContent = `E-STOP FAILED at ${time}: ${failure}. Stop the robot another way.`;
    return;
  }
  const parts = [];
  for (const robot of answer.robots || []) {
    const did = [];
    if (robot.streams_stopped.length) did.push(`ended streams on ${robot.streams_stopped.join(", ")}`);
    if (robot.zeroed_topics.length) did.push(`zero sent on ${robot.zeroed_topics.join(", ")}`);
    if (robot.cancels.length) did.push(`cancelled ${robot.cancels.join("; ")}`);
    if (robot.failures.length) did.push(`FAILED: ${robot.failures.join("; ")}`);
    parts.push(`${robot.robot}: ${did.length ? did.join("; ") : "nothing was running"}`);
  }
  shown.classList.toggle("failed", (answer.robots || []).some((robot) => robot.failures.length));
  shown.textContent = `E-STOP latched at ${time}. ${parts.join(". ")}.`;
}

$("estop").addEventListener("click", estop);
$("release").addEventListener("click", () => post("/api/release"));
$("camera-form").addEventListener("submit", (event) => {
  event.preventDefault();
  post("/api/camera", { topic: $("camera-topic").value.trim() });
});
$("map-form").addEventListener("submit", (event) => {
  event.preventDefault();
  post("/api/map", { topic: $("map-topic").value.trim(), base_frame: $("map-base").value.trim() });
});
$("camera-off").addEventListener("click", () => post("/api/camera", { topic: "" }));
if (link) showLink();
if (!secret && link) {
  // A tab opened by a link answers its one confirmation; the whole console needs the secret.
  $("main").hidden = true;
  $("link").textContent = "one confirmation";
} else if (secret) {
  listen();
  loadImageTopics();
} else {
  // Nothing but E-STOP can work here: say so instead of showing a console that looks live.
  $("no-secret").hidden = false;
  $("link").textContent = "no secret: E-STOP only";
  for (const id of ["robots-section", "pending-section", "running-section", "camera-section", "map-section", "audit-section"]) {
    $(id).hidden = true;
  }
}
