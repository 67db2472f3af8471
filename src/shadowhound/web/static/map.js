// The dashboard's map: a top-down view of the odom frame (x to the right, y up) with the grid,
// geofence, named places, the path walked, a dry run's predicted path and the robot.
// `view` holds pose, trail, predicted, world and estop (see app.js).
export function drawMap(canvas, view) {
  const ctx = canvas.getContext("2d");
  const width = canvas.width;
  const height = canvas.height;
  const points = [...view.trail, ...view.predicted, view.pose];
  let span = 2.5; // metres from the centre shown at least
  const cx = (Math.max(...points.map((p) => p.x)) + Math.min(...points.map((p) => p.x))) / 2;
  const cy = (Math.max(...points.map((p) => p.y)) + Math.min(...points.map((p) => p.y))) / 2;
  for (const p of points) span = Math.max(span, Math.abs(p.x - cx) + 1, Math.abs(p.y - cy) + 1);
  const scale = Math.min(width, height) / (2 * span);
  // x to the right, y up (the odom frame seen from above)
  const sx = (x) => width / 2 + (x - cx) * scale;
  const sy = (y) => height / 2 - (y - cy) * scale;

  ctx.fillStyle = "#fbfbf8";
  ctx.fillRect(0, 0, width, height);
  ctx.strokeStyle = "#e3e3dc";
  ctx.lineWidth = 1;
  const step = span > 8 ? 2 : 1;
  for (let g = Math.floor(cx - 2 * span); g <= cx + 2 * span; g += step) {
    line(ctx, sx(g), 0, sx(g), height);
  }
  for (let g = Math.floor(cy - 2 * span); g <= cy + 2 * span; g += step) {
    line(ctx, 0, sy(g), width, sy(g));
  }
  ctx.strokeStyle = "#d08c8c";
  ctx.setLineDash([6, 4]);
  ctx.beginPath();
  ctx.arc(sx(0), sy(0), view.world.geofence_radius * scale, 0, 2 * Math.PI);
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.fillStyle = "#555";
  ctx.font = "12px system-ui, sans-serif";
  for (const [name, [x, y]] of Object.entries(view.world.places)) {
    ctx.fillRect(sx(x) - 3, sy(y) - 3, 6, 6);
    ctx.fillText(name, sx(x) + 5, sy(y) - 5);
  }
  polyline(ctx, view.predicted, sx, sy, "#7a9cc6", [4, 4]);
  polyline(ctx, view.trail, sx, sy, "#2f7d32", []);
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

function line(ctx, x1, y1, x2, y2) {
  ctx.beginPath();
  ctx.moveTo(x1, y1);
  ctx.lineTo(x2, y2);
  ctx.stroke();
}

function polyline(ctx, points, sx, sy, colour, dash) {
  if (points.length < 2) return;
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2;
  ctx.setLineDash(dash);
  ctx.beginPath();
  points.forEach((p, i) => (i ? ctx.lineTo(sx(p.x), sy(p.y)) : ctx.moveTo(sx(p.x), sy(p.y))));
  ctx.stroke();
  ctx.setLineDash([]);
}
