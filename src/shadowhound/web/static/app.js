// ShadowHound dashboard: plain JavaScript modules, no build step. Talks to the app's own /api and
// /ws/status; every robot action goes through the HTTP API (the WebSocket only reports).
import { drawMap as draw } from "./map.js";
import { renderHistory, renderKv, renderSteps, updateStep } from "./render.js";
import { setupDrive } from "./drive.js";
import { setupTalk } from "./talk.js";

const $ = (selector) => document.querySelector(selector);
const TOKEN_KEY = "shadowhound.token";
const RECENT_KEY = "shadowhound.recent";

const view = {
  token: localStorage.getItem(TOKEN_KEY) || "",
  estop: false,
  current: null, // web mission id the step list follows
  shown: null, // web mission id the step list was last drawn for
  finished: new Map(), // the last final records by mission id (they may overtake the POST answer)
  pose: { x: 0, y: 0, yaw: 0 },
  trail: [{ x: 0, y: 0 }],
  predicted: [], // the planned path of the current mission, or of the last dry run
  grid: null, // the occupancy grid's layout (/api/map), drawn once its image has loaded
  gridImage: null,
  objects: [], // known objects: name, x, y, radius, confidence
  world: { places: {}, patrol_route: [], geofence_radius: 10, geofence_polygon: [] },
  approval: null,
  drive: null, // the teleop pad (drive.js), told when driving was switched off elsewhere
  socketFailures: 0,
};

// A token can arrive in the URL fragment (never sent to the server): #token=...
if (location.hash.startsWith("#token=")) {
  view.token = decodeURIComponent(location.hash.slice(7));
  localStorage.setItem(TOKEN_KEY, view.token);
  history.replaceState(null, "", location.pathname);
}

// -- HTTP ---------------------------------------------------------------------------------

// `body`: an object sent as JSON, or a Blob sent as it is (a recording) with `type`.
async function api(method, path, body, type) {
  const headers = { Accept: "application/json" };
  const raw = body instanceof Blob;
  if (body !== undefined) headers["Content-Type"] = raw ? (type || body.type) : "application/json";
  if (view.token) headers.Authorization = "Bearer " + view.token;
  let response;
  try {
    response = await fetch(path, {
      method, headers, body: body === undefined ? undefined : raw ? body : JSON.stringify(body),
    });
  } catch (error) {
    return { ok: false, status: 0, data: { detail: "the dashboard server is not reachable" } };
  }
  let data = null;
  try { data = await response.json(); } catch (error) { data = null; }
  if (response.status === 401) $("#auth").hidden = false;
  return { ok: response.ok, status: response.status, data };
}

function detail(data) {
  if (!data) return "no answer from the server";
  if (typeof data.detail === "string") return data.detail;
  return JSON.stringify(data.detail !== undefined ? data.detail : data);
}

function withToken(path) {
  if (!view.token) return path;
  return path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(view.token);
}

// `about` says what the message is about ("mission", "estop"), so a later outcome of the
// same thing replaces it: a mission's result its "accepted", a release the e-stop's note.
function say(selector, text, kind, about) {
  const element = $(selector);
  element.textContent = text;
  element.dataset.kind = kind || "info";
  element.dataset.about = about || "";
}

function unsay(selector, about) {
  if ($(selector).dataset.about === about) say(selector, "", "info");
}

// -- missions -----------------------------------------------------------------------------

async function submitMission(dryRun) {
  const command = $("#command").value.trim();
  if (!command) {
    say("#mission-msg", "Type a mission first, for example: walk forward 1 meter", "error");
    return;
  }
  const reply = await api("POST", "/api/mission", { command, dry_run: dryRun });
  if (reply.status === 202) {
    remember(command);
    view.current = reply.data.mission_id;
    say("#mission-msg", reply.data.message, "info", "mission");
    // Its events may have overtaken this answer: keep the steps they already drew.
    if (view.shown !== view.current) showCurrent(command + (dryRun ? " (dry run)" : ""), []);
    // A quick mission (a dry run) may even have finished already.
    const record = view.finished.get(view.current);
    if (record) showResult(record);
  } else {
    say("#mission-msg", "Refused: " + detail(reply.data), "error",
      reply.status === 409 ? "estop" : "mission");
  }
}

function showCurrent(text, steps) {
  view.shown = view.current;
  $("#current").hidden = false;
  $("#current-text").textContent = text;
  $("#progress").value = 0;
  $("#result").textContent = "";
  $("#result").dataset.kind = "";
  $("#cancel").hidden = false; // until the mission ends
  $("#spoken").replaceChildren();
  renderSteps($("#steps"), steps);
}

// What the robot said (voice.say): a line under the steps; spoken by the browser too when the
// person turned that on. Words not said aloud (over the rate, no voice) show why.
function showSpoken(message) {
  const line = document.createElement("li");
  line.dataset.aloud = String(message.aloud);
  line.textContent = (message.aloud ? "said: " : "not said aloud (" + message.why_silent + "): ") +
    "\u201c" + message.text + "\u201d";
  $("#spoken").append(line);
  if (message.aloud && $("#voice-here").checked && "speechSynthesis" in window) {
    window.speechSynthesis.speak(new SpeechSynthesisUtterance(message.text));
  }
}

function showResult(record) {
  const result = record.result || record;
  for (const step of result.steps || []) updateStep($("#steps"), step);
  const text = record.response || result.response || record.error || "no result";
  $("#result").textContent = text;
  $("#result").dataset.kind = record.success || result.success ? "ok" : "error";
  $("#cancel").hidden = true;
  unsay("#mission-msg", "mission"); // the outcome replaces "accepted; it starts now"
  if (record.mission_id !== view.spokenResult) {
    view.spokenResult = record.mission_id;
    speakAnswer(text);
  }
  if (result.success) $("#progress").value = 1;
  if (result.dry_run) {
    view.predicted = (result.predicted_path || []).map((p) => ({ x: p.x, y: p.y }));
    drawMap();
  }
}

// Results and chat answers read out by the browser, when the person turned that on.
function speakAnswer(text) {
  if (!$("#speak-answers").checked || !("speechSynthesis" in window) || !text) return;
  window.speechSynthesis.speak(new SpeechSynthesisUtterance(text));
}

// A mission started by voice: followed like one typed and run.
function spokenMission(command, missionId) {
  remember(command);
  $("#command").value = command;
  view.current = missionId;
  say("#mission-msg", "Heard and started: \u201c" + command + "\u201d", "info", "mission");
  if (view.shown !== view.current) showCurrent(command, []);
  const record = view.finished.get(view.current);
  if (record) showResult(record);
}

function remember(command) {
  let recent = JSON.parse(localStorage.getItem(RECENT_KEY) || "[]");
  recent = [command, ...recent.filter((c) => c !== command)].slice(0, 8);
  localStorage.setItem(RECENT_KEY, JSON.stringify(recent));
  renderRecent();
}

function renderRecent() {
  const recent = JSON.parse(localStorage.getItem(RECENT_KEY) || "[]");
  $("#recent").replaceChildren(...recent.map((c) => new Option(c)));
  $("#recent-list").replaceChildren(...recent.map((command) => {
    const chip = document.createElement("button");
    chip.type = "button";
    chip.className = "chip";
    chip.textContent = command;
    chip.addEventListener("click", () => { $("#command").value = command; $("#command").focus(); });
    return chip;
  }));
}

async function refreshHistory() {
  const reply = await api("GET", "/api/missions?limit=30");
  if (reply.ok) renderHistory($("#history"), reply.data.missions);
}

// -- e-stop and approvals -----------------------------------------------------------------

async function pressEstop() {
  setEstop(true); // show it at once; the answer confirms
  const reply = await api("POST", "/api/estop");
  if (!reply.ok) {
    say("#mission-msg", "E-stop request failed: " + detail(reply.data), "error");
    return;
  }
  say("#mission-msg", reply.data.message, "error", "estop");
  renderRobot(reply.data.robot); // the robot as it was once stopped, before the next tick
}

async function releaseEstop() {
  const reply = await api("POST", "/api/estop/release");
  if (reply.ok) setEstop(reply.data.estop);
  else say("#mission-msg", "Release failed: " + detail(reply.data), "error");
}

function setEstop(latched) {
  if (!latched) unsay("#mission-msg", "estop"); // its notes and refusals are over
  view.estop = latched;
  $("#estop-banner").hidden = !latched;
  $("#release").hidden = !latched;
  document.body.classList.toggle("estopped", latched);
}

function showApproval(request) {
  view.approval = request;
  $("#approval").hidden = !request;
  if (!request) return;
  $("#approval-text").textContent = "“" + request.mission + "” waits for your decision.";
  $("#approval-reasons").replaceChildren(...request.reasons.map((r) => {
    const item = document.createElement("li");
    item.textContent = r;
    return item;
  }));
}

async function decide(approve) {
  if (!view.approval) return;
  const path = "/api/approval/" + view.approval.request_id + (approve ? "/approve" : "/reject");
  const reply = await api("POST", path);
  if (!reply.ok) say("#mission-msg", detail(reply.data), "error");
  showApproval(null);
}

// -- live state ---------------------------------------------------------------------------

function applyStatus(status) {
  if (!status) return;
  $("#status-pill").textContent = status.status + (status.current_skill ? " · " +
    status.current_skill : "");
  $("#status-pill").dataset.status = status.status;
  if (status.estop !== view.estop) setEstop(status.estop);
  if (status.mission_id && status.mission_id === view.current) {
    $("#progress").value = status.progress || 0;
  }
  if ((status.pending_approval || null) !== null && !view.approval) {
    showApproval(status.pending_approval);
  } else if (!status.pending_approval && view.approval) {
    showApproval(null);
  }
  if (status.robot) renderRobot(status.robot);
  if (typeof status.teleop === "boolean" && view.drive) view.drive.sync(status.teleop);
}

function renderRobot(robot) {
  if (robot.connected === false && robot.posture === undefined) {
    renderKv($("#robot"), { connected: "no: " + (robot.error || "no state") });
    return;
  }
  renderKv($("#robot"), {
    posture: robot.posture,
    battery: Number.isFinite(robot.battery) ? robot.battery.toFixed(1) + " %" : "unknown",
    moving: robot.moving ? "yes" : "no",
    "e-stop": robot.estopped ? "latched" : "released",
    heading: Number.isFinite(robot.yaw_deg) ? Math.round(robot.yaw_deg) + "°" : "unknown",
    travelled: metres(robot.distance_travelled),
    turned: Number.isFinite(robot.angle_turned) ?
      Math.round(robot.angle_turned * 180 / Math.PI) + "°" : "unknown",
    connected: robot.connected ? "yes" : "no",
    ...(robot.blocked_by ? { "blocked by": robot.blocked_by } : {}),
  });
  movePose(robot);
}

function metres(value) {
  return Number.isFinite(value) ? value.toFixed(2) + " m" : "unknown";
}

function movePose(robot) {
  // null: the robot reported a position that is not a number (odometry that lies). The map
  // keeps the last known pose rather than guess one.
  if (![robot.x, robot.y, robot.yaw].every(Number.isFinite)) {
    $("#map").dataset.unknown = "true";
    $("#pose").textContent = "position unknown: the odometry reports no number";
    return;
  }
  delete $("#map").dataset.unknown;
  view.pose = { x: robot.x, y: robot.y, yaw: robot.yaw };
  const last = view.trail[view.trail.length - 1];
  if (!last || Math.hypot(robot.x - last.x, robot.y - last.y) > 0.01) {
    view.trail.push({ x: robot.x, y: robot.y });
    if (view.trail.length > 2000) view.trail.shift();
  }
  const map = $("#map");
  map.dataset.x = robot.x.toFixed(3);
  map.dataset.y = robot.y.toFixed(3);
  map.dataset.yaw = robot.yaw.toFixed(3);
  $("#pose").textContent = "x " + metres(robot.x) + " · y " + metres(robot.y) + " · heading " +
    Math.round(robot.yaw_deg) + "°";
  drawMap();
}

function onEvent(message) {
  switch (message.kind) {
    case "snapshot":
      applyStatus(message.status);
      renderHistory($("#history"), message.missions || []);
      break;
    case "state":
      applyStatus(message);
      break;
    case "mission_started":
      if (!view.current || message.mission_id !== view.current) {
        view.current = message.mission_id; // a mission from another client or interface
      }
      showCurrent(message.mission, []);
      break;
    case "plan_ready":
      if (message.mission_id === view.current) renderSteps($("#steps"), message.plan.steps);
      // The mission about to run: its planned path, and its walked path from here.
      view.predicted = (message.path || []).map((p) => ({ x: p.x, y: p.y }));
      view.trail = [{ x: view.pose.x, y: view.pose.y }];
      drawMap();
      break;
    case "step_started":
    case "step_finished":
      if (message.mission_id === view.current) updateStep($("#steps"), message.step);
      break;
    case "mission_finished":
      if (message.mission_id === view.current) showResult(message.result);
      refreshHistory();
      refreshWorld(); // a mission may have changed the map or seen objects
      break;
    case "mission_record":
      view.finished.set(message.mission_id, message);
      if (view.finished.size > 20) view.finished.delete(view.finished.keys().next().value);
      if (message.mission_id === view.current) showResult(message);
      refreshHistory();
      loadDiagnostics();
      break;
    case "mission_queued":
      refreshHistory();
      break;
    case "estop":
      setEstop(message.latched);
      break;
    case "spoken":
      if (message.mission_id === view.current) showSpoken(message);
      break;
    case "approval_required":
      showApproval(message.request);
      break;
    case "approval_decided":
      showApproval(null);
      break;
    default:
      break;
  }
}

function connect() {
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  const protocols = ["shadowhound"];
  if (view.token) protocols.push("bearer." + view.token);
  const socket = new WebSocket(scheme + location.host + "/ws/status", protocols);
  socket.onopen = () => { view.socketFailures = 0; setConn("live"); };
  socket.onmessage = (event) => {
    try { onEvent(JSON.parse(event.data)); } catch (error) { console.error(error); }
  };
  socket.onclose = () => {
    view.socketFailures += 1;
    setConn("offline");
    // Back off up to 5 s; meanwhile poll the status so the page stays roughly current.
    setTimeout(connect, Math.min(5000, 250 * 2 ** view.socketFailures));
    pollStatus();
  };
}

async function pollStatus() {
  const reply = await api("GET", "/api/status");
  if (reply.ok) applyStatus(reply.data);
}

function setConn(state) {
  $("#conn").dataset.state = state;
  $("#conn").textContent = state;
}

function drawMap() {
  draw($("#map"), view, { labels: $("#map-labels"), scale: $("#map-scale") });
}

// The names and the scale bar are laid out in CSS pixels: again when the map's size changes.
let redraw = 0;
function drawMapSoon() {
  cancelAnimationFrame(redraw);
  redraw = requestAnimationFrame(drawMap);
}

// -- panels fetched once or now and then --------------------------------------------------

async function loadWorld() {
  if (!(await refreshWorld())) return;
  view.trail = [{ x: view.pose.x, y: view.pose.y }];
  drawMap();
}

// Places, objects and the grid's layout; the grid image only when its version changed.
async function refreshWorld() {
  if (document.hidden && view.grid) return false;
  const reply = await api("GET", "/api/map");
  if (!reply.ok) return false;
  view.world = reply.data;
  view.objects = reply.data.objects || [];
  renderObjects();
  const grid = reply.data.grid || null;
  if (!grid) {
    view.grid = null;
    view.gridImage = null;
  } else if (!view.grid || view.grid.version !== grid.version || !view.gridImage) {
    const image = await loadGridImage(grid.url);
    if (image) {
      view.grid = grid;
      view.gridImage = image;
    }
  }
  movePose(reply.data.robot);
  return true;
}

async function loadGridImage(url) {
  const headers = view.token ? { Authorization: "Bearer " + view.token } : {};
  try {
    const response = await fetch(url, { headers });
    if (!response.ok) return null;
    return await createImageBitmap(await response.blob());
  } catch (error) {
    return null;
  }
}

function renderObjects() {
  $("#map-objects").replaceChildren(...view.objects.map((o) => {
    const item = document.createElement("li");
    item.dataset.name = o.name;
    item.textContent = o.name + " · " + o.x.toFixed(1) + ", " + o.y.toFixed(1) + " m" +
      (o.confidence < 1 ? " · " + Math.round(o.confidence * 100) + " %" : "");
    return item;
  }));
}

async function loadSkills() {
  const reply = await api("GET", "/api/skills");
  if (!reply.ok) return;
  $("#skills").replaceChildren(...reply.data.skills.map((s) => {
    const item = document.createElement("li");
    const name = document.createElement("code");
    name.textContent = s.name;
    item.append(name, " " + s.description);
    return item;
  }));
}

async function loadDiagnostics() {
  if (document.hidden) return;
  const reply = await api("GET", "/api/diagnostics");
  if (!reply.ok) return;
  const d = reply.data;
  $("#robot-badge").textContent = d.robot_description || d.robot_name || "";
  // The last mission's refusals are in its response: the errors row leaves them out, so no
  // refusal shows twice (an earlier mission's refusal is one of the recent errors).
  const refusals = d.refusals || [];
  const errors = (d.errors || []).filter((e) => !refusals.some((r) => e.includes(r)));
  renderKv($("#diag"), {
    status: d.status, robot: d.robot_description || d.robot_name, backend: d.agent_backend,
    model: d.agent_model, "last mission": d.last_mission || "none",
    "recent errors": errors.slice(-3).join(" | ") || "none",
    "live clients": d.web.clients, queued: d.web.queued,
  });
}

function startCamera() {
  const img = $("#camera");
  img.onerror = () => {
    say("#camera-msg", "no camera image yet; retrying", "info");
    setTimeout(() => { img.src = withToken("/api/camera/stream?fps=5&t=" + Date.now()); }, 3000);
  };
  img.onload = () => say("#camera-msg", "", "info");
  img.src = withToken("/api/camera/stream?fps=5");
}

async function chat(event) {
  event.preventDefault();
  const text = $("#chat-text").value.trim();
  if (!text) return;
  $("#chat-text").value = "";
  addChat("you", text);
  const reply = await api("POST", "/api/chat", { text });
  addChat("robot", reply.ok ? reply.data.answer : "(" + detail(reply.data) + ")");
  if (reply.ok) speakAnswer(reply.data.answer);
}

function addChat(who, text) {
  const line = document.createElement("p");
  line.dataset.who = who;
  line.textContent = text;
  $("#chat-log").append(line);
  $("#chat-log").scrollTop = $("#chat-log").scrollHeight;
}

// -- start --------------------------------------------------------------------------------

function start() {
  $("#mission-form").addEventListener("submit", (event) => {
    event.preventDefault();
    submitMission(false);
  });
  $("#dry-run").addEventListener("click", () => submitMission(true));
  $("#cancel").addEventListener("click", async () => {
    if (!view.current) return;
    const reply = await api("POST", "/api/missions/" + view.current + "/cancel");
    if (!reply.ok) say("#mission-msg", detail(reply.data), "error");
  });
  $("#estop").addEventListener("click", pressEstop);
  window.addEventListener("resize", drawMapSoon);
  $("#release").addEventListener("click", releaseEstop);
  $("#approve").addEventListener("click", () => decide(true));
  $("#reject").addEventListener("click", () => decide(false));
  $("#chat-form").addEventListener("submit", chat);
  $("#auth").addEventListener("submit", (event) => {
    event.preventDefault();
    view.token = $("#token").value.trim();
    localStorage.setItem(TOKEN_KEY, view.token);
    location.reload();
  });
  document.addEventListener("keydown", (event) => {
    // Esc stops the robot, except while typing (Esc also closes the input's suggestions).
    if (event.key === "Escape" && event.target.tagName !== "INPUT") pressEstop();
  });
  view.drive = setupDrive({
    fetch: api,
    detail,
    message: (text, kind) => say("#drive-msg", text, kind),
  });
  setupTalk({
    fetch: api,
    detail,
    message: (text, kind) => say("#talk-msg", text, kind),
    heard: (text) => { $("#heard").textContent = text ? "Heard: \u201c" + text + "\u201d" : ""; },
    mission: (command, missionId) => {
      say("#talk-msg", "", "info");
      spokenMission(command, missionId);
    },
    estop: (data) => {
      setEstop(true);
      say("#talk-msg", "", "info");
      say("#mission-msg", data.message, "error", "estop");
    },
    confirm: (text) => {
      $("#command").value = text;
      say("#talk-msg", "Check the words, then press Run to start (speech.confirm)", "info");
      $("#command").focus();
    },
  });
  renderRecent();
  drawMap();
  loadWorld();
  loadSkills();
  refreshHistory();
  loadDiagnostics();
  setInterval(loadDiagnostics, 3000);
  setInterval(refreshWorld, 3000);
  connect();
  startCamera();
}

start();
