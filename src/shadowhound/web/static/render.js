// Drawing lists for the dashboard: steps, history and key/value panels. DOM only, no state.

export function renderSteps(list, steps) {
  list.replaceChildren();
  steps.forEach((step, i) => list.append(stepItem({ index: i + 1, status: "pending", ...step })));
}

function stepItem(step) {
  const item = document.createElement("li");
  item.dataset.index = step.index;
  fillStep(item, step);
  return item;
}

function fillStep(item, step) {
  const args = Object.entries(step.args || {})
    .filter(([, value]) => value !== null)
    .map(([key, value]) => key + "=" + shown(value)).join(", ");
  item.dataset.status = step.status;
  item.textContent = step.skill + "(" + args + ")";
  const watches = (step.watches || []).map((w) => w.words || w.when + " " + w.kind);
  if (watches.length) {
    const watching = document.createElement("span");
    watching.className = "watch";
    watching.textContent = " " + watches.join("; ");
    item.append(watching);
  }
  const note = step.error || step.output;
  if (note) {
    const span = document.createElement("span");
    span.className = "note";
    span.textContent = " — " + note;
    item.append(span);
  }
}

export function updateStep(list, step) {
  let item = list.querySelector('li[data-index="' + step.index + '"]');
  if (!item) {
    item = stepItem(step);
    list.append(item);
  }
  fillStep(item, step);
}

// A number as people read it: at most two decimals (0.3333 -> 0.33, 1.0 -> 1).
function shown(value) {
  return typeof value === "number" ? String(Number(value.toFixed(2))) : String(value);
}

// A dry run is "dry run" (its record's status is the agent's idle: nothing ran), with what it
// found; a mission is its status and response.
export function renderHistory(list, missions) {
  list.replaceChildren(...missions.map((m) => {
    const item = document.createElement("li");
    const head = document.createElement("strong");
    head.textContent = m.command;
    const body = document.createElement("span");
    if (m.dry_run) {
      item.dataset.status = "dry-run";
      item.dataset.ok = String(m.success === true);
      const found = (m.response || "").replace(/^Dry run:\s*/, "");
      body.textContent = " dry run" + (found ? ": " + found : m.state ? " " + m.state : "");
    } else {
      item.dataset.status = m.status;
      body.textContent = " " + m.status + (m.response ? ": " + m.response : "");
    }
    item.append(head, body);
    return item;
  }));
}

export function renderKv(list, values) {
  list.replaceChildren();
  for (const [key, value] of Object.entries(values)) {
    const term = document.createElement("dt");
    term.textContent = key;
    const def = document.createElement("dd");
    def.textContent = typeof value === "object" && value !== null ? JSON.stringify(value)
      : String(value);
    list.append(term, def);
  }
}
