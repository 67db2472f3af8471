// The dashboard's map: a top-down view of the odom frame (x to the right, y up) with the
// occupancy grid, geofence, named places, known objects, the planned path of the mission (or a
// dry run's), the path walked and the robot. `view` holds pose, trail, predicted, world, grid,
// gridImage, objects and estop (see app.js). The transform used is left on the canvas as
// data-cx, data-cy and data-scale (pixels per metre), so a test can find what it drew. Names
// (places, objects, the map's own labels) and the scale bar are HTML over the canvas, in
// `overlay` ({labels, scale}; labels.js places the names).
import { placeLabels } from "./labels.js";

const SHOW_WHOLE_GRID = 30; // metres: a grid up to this size is kept in view entirely
const SCALE_BARS = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100]; // metres
const PLACE_MARK = 3; // canvas pixels: half a place's square

export function drawMap(canvas, view, overlay) {
  const ctx = canvas.getContext("2d");
  const width = canvas.width;
  const height = canvas.height;
  const points = [...view.trail, ...view.predicted, view.pose, ...view.objects];
  const grid = view.gridImage ? view.grid : null;
  if (grid) {
    const corners = gridCorners(grid);
    const xs = corners.map((p) => p.x);
    const ys = corners.map((p) => p.y);
    if (Math.max(...xs) - Math.min(...xs) <= SHOW_WHOLE_GRID &&
        Math.max(...ys) - Math.min(...ys) <= SHOW_WHOLE_GRID) points.push(...corners);
  }
  let span = 2.5; // metres from the centre shown at least
  const cx = (Math.max(...points.map((p) => p.x)) + Math.min(...points.map((p) => p.x))) / 2;
  const cy = (Math.max(...points.map((p) => p.y)) + Math.min(...points.map((p) => p.y))) / 2;
  for (const p of points) {
    span = Math.max(span, Math.abs(p.x - cx) + 0.5, Math.abs(p.y - cy) + 0.5);
  }
  const scale = Math.min(width, height) / (2 * span);
  // x to the right, y up (the odom frame seen from above)
  const sx = (x) => width / 2 + (x - cx) * scale;
  const sy = (y) => height / 2 - (y - cy) * scale;
  canvas.dataset.cx = cx.toFixed(4);
  canvas.dataset.cy = cy.toFixed(4);
  canvas.dataset.scale = scale.toFixed(4);

  ctx.fillStyle = "#fbfbf8";
  ctx.fillRect(0, 0, width, height);
  if (grid) drawGrid(ctx, view.gridImage, grid, sx, sy, scale);
  canvas.dataset.grid = grid ? grid.version : "";
  ctx.strokeStyle = grid ? "rgba(120, 120, 110, 0.25)" : "#e3e3dc";
  ctx.lineWidth = 1;
  const step = span > 8 ? 2 : 1;
  for (let g = Math.floor(cx - 2 * span); g <= cx + 2 * span; g += step) {
    line(ctx, sx(g), 0, sx(g), height);
  }
  for (let g = Math.floor(cy - 2 * span); g <= cy + 2 * span; g += step) {
    line(ctx, 0, sy(g), width, sy(g));
  }
  drawGeofence(ctx, view.world, sx, sy, scale);
  drawObjects(ctx, view.objects, sx, sy, scale);
  ctx.fillStyle = "#555"; // places on top: a place may be at an object
  for (const [x, y] of Object.values(view.world.places)) {
    ctx.fillRect(sx(x) - PLACE_MARK, sy(y) - PLACE_MARK, 2 * PLACE_MARK, 2 * PLACE_MARK);
  }
  polyline(ctx, view.predicted, sx, sy, "#3f6fb5", [6, 4]);
  polyline(ctx, view.trail, sx, sy, "#2f7d32", []);
  if (overlay) {
    const leaders = placeLabels(overlay.labels, canvas, namedMarks(view, sx, sy, scale),
      [{ x: sx(view.pose.x), y: sy(view.pose.y), r: 12 }]);
    ctx.strokeStyle = "rgba(60, 60, 55, 0.6)";
    ctx.lineWidth = 1;
    for (const l of leaders) line(ctx, l.x1, l.y1, l.x2, l.y2);
    drawScale(overlay.scale, canvas, scale);
  }
  const { x, y, yaw } = view.pose;
  ctx.save();
  ctx.translate(sx(x), sy(y));
  ctx.rotate(-yaw);
  ctx.fillStyle = view.estop ? "#c62828" : "#1b4f8a";
  ctx.beginPath();
  ctx.moveTo(12, 0);
  ctx.lineTo(-8, 7);
  ctx.lineTo(-8, -7);
  ctx.closePath();
  ctx.fill();
  ctx.restore();
}

// The grid image's top row is the grid's last row: in the grid's own frame (origin at cell
// (0, 0)'s outer corner, rotated by origin.yaw) it spans x 0..width*res, y 0..height*res.
function drawGrid(ctx, image, grid, sx, sy, scale) {
  const metres = grid.resolution * scale;
  ctx.save();
  ctx.imageSmoothingEnabled = false;
  ctx.translate(sx(grid.origin.x), sy(grid.origin.y));
  ctx.rotate(-grid.origin.yaw);
  ctx.drawImage(image, 0, -grid.height * metres, grid.width * metres, grid.height * metres);
  ctx.restore();
}

function gridCorners(grid) {
  const { x, y, yaw } = grid.origin;
  const w = grid.width * grid.resolution;
  const h = grid.height * grid.resolution;
  const c = Math.cos(yaw);
  const s = Math.sin(yaw);
  return [[0, 0], [w, 0], [0, h], [w, h]].map(([u, v]) => ({ x: x + c * u - s * v,
    y: y + s * u + c * v }));
}

function drawGeofence(ctx, world, sx, sy, scale) {
  ctx.strokeStyle = "#d08c8c";
  ctx.lineWidth = 1.5;
  ctx.setLineDash([6, 4]);
  ctx.beginPath();
  ctx.arc(sx(0), sy(0), world.geofence_radius * scale, 0, 2 * Math.PI);
  ctx.stroke();
  const polygon = world.geofence_polygon || [];
  if (polygon.length >= 3) {
    ctx.beginPath();
    polygon.forEach(([x, y], i) => (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
    ctx.closePath();
    ctx.stroke();
  }
  ctx.setLineDash([]);
}

function drawObjects(ctx, objects, sx, sy, scale) {
  for (const o of objects) {
    ctx.fillStyle = "rgba(230, 126, 34, " + (0.35 + 0.5 * o.confidence).toFixed(2) + ")";
    ctx.strokeStyle = "#a84300";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.arc(sx(o.x), sy(o.y), objectRadius(o, scale), 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
  }
}

function objectRadius(o, scale) {
  return Math.max(4, o.radius * scale);
}

// Everything that has a name, places first: the places, the objects seen, and the obstacles
// the map itself names (the simulator's scene) that have not been seen yet.
function namedMarks(view, sx, sy, scale) {
  const seen = new Set(view.objects.map((o) => o.name));
  return [
    ...Object.entries(view.world.places).map(([name, [x, y]]) => ({
      key: "place:" + name, kind: "place", name, x: sx(x), y: sy(y), r: PLACE_MARK })),
    ...view.objects.map((o) => ({ key: "object:" + o.name, kind: "object", name: o.name,
      x: sx(o.x), y: sy(o.y), r: objectRadius(o, scale) })),
    ...(view.world.labels || []).filter((o) => !seen.has(o.name)).map((o) => ({
      key: "label:" + o.name, kind: "label", name: o.name, x: sx(o.x), y: sy(o.y),
      r: o.radius * scale })),
  ];
}

// A bar of a round length, 40 to 120 CSS pixels long where it can be.
function drawScale(element, canvas, scale) {
  const perMetre = scale * (canvas.clientWidth / canvas.width || 1); // CSS pixels
  const metres = SCALE_BARS.find((m) => m * perMetre >= 40) || SCALE_BARS[SCALE_BARS.length - 1];
  element.dataset.metres = String(metres);
  element.querySelector(".bar").style.width = (metres * perMetre).toFixed(1) + "px";
  element.querySelector(".text").textContent = metres + " m";
}

function line(ctx, x1, y1, x2, y2) {
  ctx.beginPath();
  ctx.moveTo(x1, y1);
  ctx.lineTo(x2, y2);
  ctx.stroke();
}

function polyline(ctx, points, sx, sy, colour, dash) {
  if (points.length < 2) return;
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2.5;
  ctx.setLineDash(dash);
  ctx.beginPath();
  points.forEach((p, i) => (i ? ctx.lineTo(sx(p.x), sy(p.y)) : ctx.moveTo(sx(p.x), sy(p.y))));
  ctx.stroke();
  ctx.setLineDash([]);
}
