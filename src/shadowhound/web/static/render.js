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
    .map(([key, value]) => key + "=" + value).join(", ");
  item.dataset.status = step.status;
  item.textContent = step.skill + "(" + args + ")";
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

export function renderHistory(list, missions) {
  list.replaceChildren(...missions.map((m) => {
    const item = document.createElement("li");
    item.dataset.status = m.status;
    const head = document.createElement("strong");
    head.textContent = m.command + (m.dry_run ? " (dry run)" : "");
    const body = document.createElement("span");
    body.textContent = " " + m.status + (m.response ? ": " + m.response : "");
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
