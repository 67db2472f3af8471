// Names on the map: HTML labels over the canvas (crisp at any zoom, read by screen readers and
// tests), placed so that no two overlap and none covers another named mark. Each label tries
// spots around its mark, nearest first (right, left, above, below, the diagonals), then the
// same further out; a label that had to move away gets a thin leader line to its mark.

const GAP = 3; // CSS pixels between a mark and its name
const RINGS = 6; // how far out (in label heights) a name may move before it gives up a rule

// `items`: {key, kind, name, x, y, r} with x, y, r in canvas pixels (r: the mark's radius).
// `avoid`: more marks to keep clear, {x, y, r}, e.g. the robot. Returns the leader lines to
// draw, in canvas pixels: [{x1, y1, x2, y2}].
export function placeLabels(layer, canvas, items, avoid) {
  const k = canvas.clientWidth / canvas.width || 1; // CSS pixels per canvas pixel
  const width = canvas.clientWidth;
  const height = canvas.clientHeight;
  const marks = [...items, ...avoid].map((m) => box(m.x * k, m.y * k, Math.max(3, m.r * k)));
  const old = new Map([...layer.children].map((e) => [e.dataset.key, e]));
  const placed = [];
  const leaders = [];
  for (const item of items) {
    const label = old.get(item.key) || make(layer, item);
    old.delete(item.key);
    label.textContent = item.name;
    label.dataset.kind = item.kind;
    const w = label.offsetWidth;
    const h = label.offsetHeight;
    const own = box(item.x * k, item.y * k, Math.max(3, item.r * k));
    const others = marks.filter((m) => !same(m, own));
    // Rules given up one at a time, as far as needed: clear of other marks, then inside
    // the map; never on top of another name.
    const fits = (b) => inside(b, width, height) && free(b, placed, 1);
    const spot = find(own, w, h, (b) => fits(b) && free(b, others)) ||
      find(own, w, h, (b) => fits(b) && free(b, others), 4 * RINGS) ||
      find(own, w, h, fits, 4 * RINGS) || find(own, w, h, (b) => free(b, placed, 1), 8 * RINGS);
    const { x, y, ring } = spot || { x: own.x + own.w + GAP, y: own.y, ring: 0 };
    label.style.left = x + "px";
    label.style.top = y + "px";
    placed.push({ x, y, w, h });
    if (ring > 0) {
      const cx = own.x + own.w / 2;
      const cy = own.y + own.h / 2;
      const ex = Math.min(Math.max(cx, x), x + w);
      const ey = Math.min(Math.max(cy, y), y + h);
      leaders.push({ x1: cx / k, y1: cy / k, x2: ex / k, y2: ey / k });
    }
  }
  for (const gone of old.values()) gone.remove();
  return leaders;
}

function make(layer, item) {
  const label = document.createElement("span");
  label.className = "map-label";
  label.dataset.key = item.key;
  label.dataset.name = item.name;
  layer.append(label);
  return label;
}

// The first spot around `own` (nearest ring first) that `ok` accepts, or null.
function find(own, w, h, ok, rings = RINGS) {
  const cx = own.x + own.w / 2;
  const cy = own.y + own.h / 2;
  for (let ring = 0; ring <= rings; ring += 1) {
    const d = own.w / 2 + GAP + ring * h * 0.75;
    const e = d * 0.71;
    const spots = [
      [cx + d, cy - h / 2], [cx - d - w, cy - h / 2], [cx - w / 2, cy - d - h],
      [cx - w / 2, cy + d], [cx + e, cy - e - h], [cx + e, cy + e], [cx - e - w, cy - e - h],
      [cx - e - w, cy + e],
    ];
    for (const [x, y] of spots) {
      if (ok({ x, y, w, h })) return { x, y, ring };
    }
  }
  return null;
}

function box(x, y, r) {
  return { x: x - r, y: y - r, w: 2 * r, h: 2 * r };
}

function same(a, b) {
  return a.x === b.x && a.y === b.y && a.w === b.w;
}

function inside(b, width, height) {
  return b.x >= 0 && b.y >= 0 && b.x + b.w <= width && b.y + b.h <= height;
}

// Whether `b` keeps `pad` pixels from every box.
function free(b, boxes, pad = 0) {
  return boxes.every((o) => b.x + b.w + pad <= o.x || o.x + o.w + pad <= b.x ||
    b.y + b.h + pad <= o.y || o.y + o.h + pad <= b.y);
}
