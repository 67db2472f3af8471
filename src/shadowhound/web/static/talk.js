// Push-to-talk: hold the Talk button (or the T key) to record, release to send. The recording
// goes to POST /api/speech, which has it transcribed and runs what was said as a mission; a
// spoken "stop" latches the e-stop at once. Nothing is recorded before the button is held,
// and a recording longer than the server takes (speech.max_seconds) is dropped, saying so.

const TYPES = ["audio/webm;codecs=opus", "audio/ogg;codecs=opus", "audio/webm", "audio/ogg"];

export function setupTalk(hooks) {
  const button = document.querySelector("#talk");
  let settings = null;
  let recorder = null;
  let chunks = [];
  let timer = null;
  let tooLong = false;
  let wanted = false; // held: released before the microphone opened means "do not record"

  async function load() {
    const reply = await hooks.fetch("GET", "/api/speech");
    settings = reply.ok ? reply.data : { configured: false, why: "the server did not answer" };
    button.dataset.configured = String(!!settings.configured);
    button.title = settings.configured
      ? "Hold to talk (or hold T); release to send" : settings.why;
    return settings;
  }

  async function begin() {
    if (recorder || wanted) return;
    wanted = true;
    const s = settings || await load();
    if (!s.configured) {
      wanted = false;
      hooks.message("Push-to-talk is off: " + s.why, "error");
      return;
    }
    if (!navigator.mediaDevices || !window.MediaRecorder) {
      wanted = false;
      hooks.message("This browser cannot record audio here (it needs https or localhost)",
        "error");
      return;
    }
    let stream;
    try {
      stream = await navigator.mediaDevices.getUserMedia({ audio: true });
    } catch (error) {
      wanted = false;
      hooks.message("No microphone: " + error.message, "error");
      return;
    }
    if (!wanted) { // let go while the browser asked for the microphone
      stream.getTracks().forEach((t) => t.stop());
      return;
    }
    const type = TYPES.find((t) => MediaRecorder.isTypeSupported(t)) || "";
    recorder = new MediaRecorder(stream, type ? { mimeType: type } : {});
    chunks = [];
    tooLong = false;
    const started = performance.now();
    recorder.ondataavailable = (event) => {
      if (event.data.size) chunks.push(event.data);
      // How much is recorded so far, in seconds (the page shows it; tests wait on it).
      button.dataset.recorded = ((performance.now() - started) / 1000).toFixed(1);
    };
    recorder.onstop = () => {
      stream.getTracks().forEach((t) => t.stop());
      const blob = new Blob(chunks, { type: (recorder.mimeType || type || "audio/webm") });
      recorder = null;
      if (tooLong) {
        button.dataset.state = "idle";
        hooks.message("The recording was longer than " + s.max_seconds +
          " s (speech.max_seconds) and was not sent: say one short request", "error");
      } else {
        send(blob);
      }
    };
    recorder.start(250);
    button.dataset.recorded = "0";
    button.dataset.state = "recording";
    hooks.message("Listening... release to send", "info");
    timer = setTimeout(() => { tooLong = true; finish(); }, s.max_seconds * 1000);
  }

  function finish() {
    wanted = false;
    clearTimeout(timer);
    if (recorder && recorder.state !== "inactive") {
      button.dataset.state = "sending";
      recorder.stop();
    }
  }

  async function send(blob) {
    hooks.message("Transcribing...", "info");
    const reply = await hooks.fetch("POST", "/api/speech", blob, blob.type);
    button.dataset.state = "idle";
    const data = reply.data || {};
    if (data.transcript !== undefined) hooks.heard(data.transcript);
    if (reply.status === 202) hooks.mission(data.transcript, data.mission_id);
    else if (reply.ok && data.estop) hooks.estop(data);
    else if (reply.ok && data.confirm) hooks.confirm(data.transcript);
    else hooks.message(hooks.detail(data), "error");
  }

  button.addEventListener("pointerdown", (event) => {
    event.preventDefault();
    button.setPointerCapture(event.pointerId);
    begin();
  });
  for (const kind of ["pointerup", "pointercancel", "lostpointercapture"]) {
    button.addEventListener(kind, finish);
  }
  button.addEventListener("contextmenu", (event) => event.preventDefault()); // long press
  document.addEventListener("keydown", (event) => {
    if (event.key.toLowerCase() === "t" && !event.repeat && !typing(event)) begin();
  });
  document.addEventListener("keyup", (event) => {
    if (event.key.toLowerCase() === "t" && !typing(event)) finish();
  });
  load();
}

function typing(event) {
  return ["INPUT", "TEXTAREA", "SELECT"].includes(event.target.tagName);
}
