// The teleop pad: switch "Drive" on, then drag the pad (up = forward, sideways = turn) or hold
// the keys (W/S or arrows up/down: forward/back, A/D or arrows left/right: turn, Q/E: step
// sideways, space: stop). While held, the deflection goes to /api/teleop/drive ten times a
// second, each request numbered (seq: this page's clock in ms, always growing, so the server
// drops one that arrives after a newer one, the release included); letting go sends zero at
// once. The server keeps the limits (the governor's rules, speed caps, the geofence, obstacles
// on the map), sends the robot a stop when the page goes quiet (within 0.4 s of its last
// word; the robot then brakes) and switches driving off when nobody drives for a while.

const KEYS = {
  w: [1, 0, 0], arrowup: [1, 0, 0], s: [-1, 0, 0], arrowdown: [-1, 0, 0],
  a: [0, 0, 1], arrowleft: [0, 0, 1], d: [0, 0, -1], arrowright: [0, 0, -1],
  q: [0, 1, 0], e: [0, -1, 0],
};
const KEY_DEFLECTION = 0.7;
const PERIOD_MS = 100;

export function setupDrive(hooks) {
  const toggle = document.querySelector("#drive-on");
  const pad = document.querySelector("#pad");
  const knob = pad.querySelector(".knob");
  const note = document.querySelector("#drive-note");
  const held = new Set();
  let padStick = [0, 0, 0];
  let sent = "0,0,0";
  let timer = null;
  let seq = 0;
  let switches = 0; // switch clicks so far: an answer from before the latest is out of date
  let switching = 0; // switch requests on their way
  let confirming = false; // a question to the server about the switch is on its way

  // Growing with every request, also across a reload of the page (its clock, in ms).
  function nextSeq() {
    seq = Math.max(seq + 1, Date.now());
    return seq;
  }

  // What the server says of its limits, in its own figures.
  function describe(state) {
    note.textContent = `Letting go stops at once. If this page goes quiet, the robot is sent ` +
      `a stop within ${state.stop_after} s of its last word, then brakes (about ` +
      `${state.braking} s from full speed). Nobody driving for ${state.idle_timeout} s switches driving off.`;
  }

  function stick() {
    if (padStick.some((v) => v !== 0)) return padStick;
    const sum = [0, 0, 0];
    for (const key of held) KEYS[key].forEach((v, i) => { sum[i] += v * KEY_DEFLECTION; });
    return sum.map((v) => Math.max(-1, Math.min(1, v)));
  }

  async function send() {
    const [forward, left, turn] = stick();
    const key = [forward, left, turn].join(",");
    const zero = key === "0,0,0";
    if (zero && sent === "0,0,0") return stopLoop();
    sent = key;
    const reply = await hooks.fetch("POST", "/api/teleop/drive",
      { seq: nextSeq(), forward, left, turn });
    if (!reply.ok) {
      hooks.message(hooks.detail(reply.data), "error");
      if (reply.status === 409) { setOn(false); confirm(true); }
      return;
    }
    if (reply.data.dropped) return; // a late answer: a newer request says what holds
    hooks.message(reply.data.limited ? "Limited: " + reply.data.limited : "", "info");
    if (zero) stopLoop();
  }

  function startLoop() {
    if (!timer) timer = setInterval(send, PERIOD_MS);
    send();
  }

  function stopLoop() {
    clearInterval(timer);
    timer = null;
  }

  function changed() {
    if (!toggle.checked) return;
    startLoop(); // sends the new deflection now, then every 100 ms while it is not zero
  }

  function setOn(on) {
    toggle.checked = on;
    pad.dataset.on = String(on);
    if (!on) {
      held.clear();
      padStick = [0, 0, 0];
      placeKnob(0, 0);
      stopLoop();
      sent = "0,0,0";
    }
  }

  toggle.addEventListener("change", async () => {
    const mine = ++switches;
    switching += 1;
    const reply = await hooks.fetch("POST", "/api/teleop", { on: toggle.checked });
    switching -= 1;
    if (mine !== switches) return; // clicked again meanwhile: the later answer holds
    if (!reply.ok) {
      setOn(false);
      hooks.message(hooks.detail(reply.data), "error");
      return;
    }
    setOn(reply.data.on);
    describe(reply.data);
    hooks.message(reply.data.on ? "Driving: drag the pad or hold W A S D" : "", "info");
  });

  // The status says otherwise than the switch: ask the server now (not while a switch request
  // is on its way), and believe the answer unless the switch was clicked meanwhile (a status
  // sent before a click may arrive after it).
  // Switched off by the server (`off`: a drive was refused so), say why (nobody drove for a
  // while, the e-stop).
  async function confirm(off = false) {
    if (switching || (confirming && !off)) return; // an answer on its way will say
    const mine = switches;
    confirming = true;
    const reply = await hooks.fetch("GET", "/api/teleop");
    confirming = false;
    if (!reply.ok || mine !== switches || switching) return;
    if (toggle.checked === reply.data.on && !off) return;
    setOn(reply.data.on);
    if (!reply.data.on && reply.data.ended) {
      hooks.message("Driving is off: " + reply.data.ended, "info");
    }
  }

  hooks.fetch("GET", "/api/teleop").then((reply) => { if (reply.ok) describe(reply.data); });

  function placeKnob(x, y) {
    knob.style.transform = `translate(${x}px, ${y}px)`;
  }

  function fromPointer(event) {
    const box = pad.getBoundingClientRect();
    const radius = box.width / 2;
    let dx = event.clientX - (box.left + radius);
    let dy = event.clientY - (box.top + radius);
    const length = Math.hypot(dx, dy);
    if (length > radius) { dx *= radius / length; dy *= radius / length; }
    placeKnob(dx, dy);
    const round = (v) => Math.round(v * 100) / 100;
    padStick = [round(-dy / radius), 0, round(-dx / radius)];
    changed();
  }

  pad.addEventListener("pointerdown", (event) => {
    if (!toggle.checked) { hooks.message("Switch Drive on first", "error"); return; }
    event.preventDefault();
    pad.setPointerCapture(event.pointerId);
    fromPointer(event);
  });
  pad.addEventListener("pointermove", (event) => {
    if (pad.hasPointerCapture(event.pointerId)) fromPointer(event);
  });
  for (const kind of ["pointerup", "pointercancel", "lostpointercapture"]) {
    pad.addEventListener(kind, () => {
      padStick = [0, 0, 0];
      placeKnob(0, 0);
      changed();
    });
  }

  document.addEventListener("keydown", (event) => {
    if (!toggle.checked || typing(event)) return;
    const key = event.key.toLowerCase();
    if (key === " ") {
      event.preventDefault();
      held.clear();
      padStick = [0, 0, 0];
      changed();
      return;
    }
    if (!(key in KEYS)) return;
    event.preventDefault(); // arrows would scroll the page
    if (!held.has(key)) { held.add(key); changed(); }
  });
  document.addEventListener("keyup", (event) => {
    const key = event.key.toLowerCase();
    if (held.delete(key)) changed();
  });
  // Leaving the page (or hiding it) lets go; the server's dead-man covers a lost connection.
  window.addEventListener("blur", () => { held.clear(); changed(); });
  document.addEventListener("visibilitychange", () => {
    if (document.hidden) { held.clear(); padStick = [0, 0, 0]; changed(); }
  });

  return {
    // The e-stop (or another client) switched driving off.
    sync(on) { if (toggle.checked !== on) confirm(); },
  };
}

function typing(event) {
  return ["INPUT", "TEXTAREA", "SELECT"].includes(event.target.tagName) &&
    event.target.type !== "checkbox";
}
