// The live view's page (live_view.hpp): one document, the CSS and the JavaScript inline, nothing
// fetched but the daemon's own endpoints (it works without internet). Layout, 1280 x 800:
// the status line on top; the field (600 x 440 canvas at 10, 40) with the carpet, the lines from
// the field model, the recent path (cyan), the pose (red disc, dark heading line) with its 2-sigma
// position circle and +-2-sigma heading wedge (yellow); the camera frame with the overlay
// (/frame.jpg on a 640 x 480 canvas at 630, 40, drawn 1:1; a larger frame scaled down); the match
// error over the last 5-30 s with E_TH (600 x 220 canvas at 10, 500); the pose and frame in
// numbers. Colours are part of the contract with the screenshot test
// (tests/host/test_live_view.cpp).
#include "omniloc/live_view.hpp"

namespace omniloc::live {

namespace {

constexpr std::string_view kPage = R"HTML(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>omniloc live view</title>
<style>
  html, body { margin: 0; padding: 0; background: #181818; color: #e0e0e0; font: 13px monospace; }
  #status { position: absolute; left: 10px; top: 8px; width: 1260px; height: 24px; line-height: 24px;
            white-space: pre; overflow: hidden; background: #263238; padding: 0 6px; box-sizing: border-box; }
  #field { position: absolute; left: 10px; top: 40px; }
  #camera { position: absolute; left: 630px; top: 40px; background: #000; }
  #errors { position: absolute; left: 10px; top: 500px; }
  #info { position: absolute; left: 630px; top: 530px; width: 640px; white-space: pre; line-height: 18px; }
  .k { color: #90a4ae; }
</style>
</head>
<body>
<div id="status">connecting ...</div>
<canvas id="field" width="600" height="440"></canvas>
<canvas id="camera" width="640" height="480"></canvas>
<canvas id="errors" width="600" height="220"></canvas>
<div id="info"></div>
<script>
"use strict";
const CARPET = '#2e7d32', LINE = '#ffffff', GOAL = '#9e9e9e', PATH = '#00e5ff', SIGMA = '#ffd600',
      WEDGE = 'rgba(255, 214, 0, 0.35)', MARKER = '#ff1744', HEADING = '#111111', ERR = '#ffab00', ETH = '#ef5350';
const fieldCanvas = document.getElementById('field'), fctx = fieldCanvas.getContext('2d');
const camCanvas = document.getElementById('camera'), cctx = camCanvas.getContext('2d');
const errCanvas = document.getElementById('errors'), ectx = errCanvas.getContext('2d');
let field = null, state = null, map = null;

// Field frame (cm, x right, y up, [0, total]) to canvas pixels: the carpet as large as fits, centred.
function makeMap(f) {
  const s = Math.min(fieldCanvas.width / f.total_x_cm, fieldCanvas.height / f.total_y_cm);
  const w = Math.floor(f.total_x_cm * s), h = Math.floor(f.total_y_cm * s);
  const ox = Math.floor((fieldCanvas.width - w) / 2), oy = Math.floor((fieldCanvas.height - h) / 2);
  return { s, w, h, ox, oy, x: (x) => ox + x * s, y: (y) => oy + h - y * s };
}

function drawField() {
  const c = fctx, W = fieldCanvas.width, H = fieldCanvas.height;
  c.fillStyle = '#202020';
  c.fillRect(0, 0, W, H);
  if (!field) return;
  const m = map;
  c.fillStyle = CARPET;
  c.fillRect(m.ox, m.oy, m.w, m.h);
  c.strokeStyle = LINE;
  c.fillStyle = LINE;
  c.lineWidth = Math.max(1, field.line_width_cm * m.s);
  for (const [ax, ay, bx, by] of field.segments) {
    c.beginPath(); c.moveTo(m.x(ax), m.y(ay)); c.lineTo(m.x(bx), m.y(by)); c.stroke();
  }
  for (const [cx, cy, r, a0, a1] of field.arcs) {
    c.beginPath(); c.arc(m.x(cx), m.y(cy), r * m.s, -a0 * Math.PI / 180, -a1 * Math.PI / 180, true); c.stroke();
  }
  for (const [cx, cy, r] of field.discs) {
    c.beginPath(); c.arc(m.x(cx), m.y(cy), Math.max(1, r * m.s), 0, 2 * Math.PI); c.fill();
  }
  c.strokeStyle = GOAL;
  for (const [x, back, y0, y1] of field.goals) {
    c.beginPath(); c.moveTo(m.x(x), m.y(y0)); c.lineTo(m.x(back), m.y(y0)); c.lineTo(m.x(back), m.y(y1));
    c.lineTo(m.x(x), m.y(y1)); c.stroke();
  }
  if (!state) return;
  if (state.path.length > 1) {
    c.strokeStyle = PATH;
    c.lineWidth = 2;
    c.beginPath();
    state.path.forEach(([t, x, y], i) => (i ? c.lineTo(m.x(x), m.y(y)) : c.moveTo(m.x(x), m.y(y))));
    c.stroke();
  }
  if (!state.has_pose) return;
  const p = state.pose, px = m.x(p.x_cm), py = m.y(p.y_cm), yaw = p.yaw_deg * Math.PI / 180;
  // Heading uncertainty: a wedge of +-2 sigma around the heading; position: the 2-sigma circle.
  // Neither without an uncertainty (source none: no pose from a fix).
  if (p.uncertainty_yaw_deg !== undefined) {
    const dyaw = Math.min(Math.PI, 2 * p.uncertainty_yaw_deg * Math.PI / 180);
    c.fillStyle = WEDGE;
    c.beginPath(); c.moveTo(px, py); c.arc(px, py, 34, -yaw - dyaw, -yaw + dyaw); c.closePath(); c.fill();
  }
  c.strokeStyle = HEADING;
  c.lineWidth = 2;
  c.beginPath(); c.moveTo(px, py); c.lineTo(px + 20 * Math.cos(yaw), py - 20 * Math.sin(yaw)); c.stroke();
  c.fillStyle = MARKER;
  c.beginPath(); c.arc(px, py, 7, 0, 2 * Math.PI); c.fill();
  // On top of the marker: a tracked pose's 2-sigma circle is often smaller than the marker.
  if (p.uncertainty_cm === undefined) return;
  c.strokeStyle = SIGMA;
  c.lineWidth = 1.5;
  c.beginPath(); c.arc(px, py, Math.max(1, 2 * p.uncertainty_cm * m.s), 0, 2 * Math.PI); c.stroke();
}

function drawErrors() {
  const c = ectx, W = errCanvas.width, H = errCanvas.height, L = 40, B = 20;
  c.fillStyle = '#202020';
  c.fillRect(0, 0, W, H);
  c.fillStyle = '#e0e0e0';
  c.fillText('match error (normalised, daemon time)', L + 4, 12);
  if (!state) return;
  const e = state.errors, eth = state.e_th;
  let top = 2 * eth;
  for (const [, v] of e) if (v !== null && v > top) top = Math.min(v, 10 * eth);
  // The time axis spans the history, at least 5 s and at most 30 s.
  const t1 = e.length ? e[e.length - 1][0] : 0, span = Math.min(30000, Math.max(5000, e.length ? t1 - e[0][0] : 0));
  const t0 = t1 - span;
  c.fillStyle = '#e0e0e0';
  c.fillText('-' + (span / 1000).toFixed(0) + ' s', L, H - 6);
  c.fillText('now', W - 30, H - 6);
  const X = (t) => L + (W - L - 6) * (t - t0) / span, Y = (v) => H - B - (H - B - 18) * Math.min(v, top) / top;
  c.strokeStyle = '#616161';
  c.lineWidth = 1;
  c.beginPath(); c.moveTo(L, 18); c.lineTo(L, H - B); c.lineTo(W - 6, H - B); c.stroke();
  c.fillText(top.toFixed(1), 4, 24);
  c.fillText('0', 4, H - B);
  c.strokeStyle = ETH;
  c.setLineDash([4, 4]);
  c.beginPath(); c.moveTo(L, Y(eth)); c.lineTo(W - 6, Y(eth)); c.stroke();
  c.setLineDash([]);
  c.fillStyle = ETH;
  c.fillText('E_TH ' + eth, W - 70, Y(eth) - 4);
  c.strokeStyle = ERR;
  c.lineWidth = 2;
  c.beginPath();
  let open = false;
  for (const [t, v] of e) {
    if (v === null) { open = false; continue; }
    if (open) c.lineTo(X(t), Y(v)); else c.moveTo(X(t), Y(v));
    open = true;
  }
  c.stroke();
}

function f1(v) { return v === undefined || v === null ? '-' : Number(v).toFixed(1); }

function drawInfo() {
  const el = document.getElementById('info');
  if (!state || !state.pose) { el.textContent = 'no pose yet'; return; }
  const p = state.pose, fr = state.frame;
  el.textContent =
    'status   ' + p.status + '   source ' + p.source + '   seq ' + p.seq + '\n' +
    'pose     x ' + f1(p.x_cm) + ' cm   y ' + f1(p.y_cm) + ' cm   yaw ' + f1(p.yaw_deg) + ' deg\n' +
    'sigma    ' + (p.uncertainty_cm === undefined ? '-' : Number(p.uncertainty_cm).toFixed(2) + ' cm   ' + Number(p.uncertainty_yaw_deg).toFixed(2) + ' deg') + '\n' +
    'error    ' + (p.match_error === undefined ? '-' : Number(p.match_error).toFixed(2)) + '   (E_TH ' + state.e_th + ')\n' +
    'velocity ' + f1(p.vx_cm_s) + ', ' + f1(p.vy_cm_s) + ' cm/s   ' + f1(p.omega_deg_s) + ' deg/s\n' +
    'frame    t ' + f1(fr.overlay_t_ms) + ' ms   rays seen ' + fr.rays_seen + '   crossings ' + fr.crossings +
    (fr.usable ? '' : '   no measurement: ' + fr.reason) + '\n' +
    'camera   rays grey, crossings magenta, carpet boundary red, field model at the pose yellow';
}

function draw() {
  drawField();
  drawErrors();
  drawInfo();
  document.getElementById('status').textContent = state && state.status_line ? state.status_line : 'waiting for the first status line';
}

async function loadField() {
  try {
    const r = await fetch('/field.json', { cache: 'no-store' });
    field = await r.json();
    map = makeMap(field);
    draw();
  } catch (e) {
    setTimeout(loadField, 1000);
  }
}

async function poll() {
  try {
    const r = await fetch('/state.json', { cache: 'no-store' });
    if (r.ok) { state = await r.json(); draw(); }
  } catch (e) {
    document.getElementById('status').textContent = 'daemon not answering';
  }
  setTimeout(poll, 200);
}

function loadFrame() {
  const img = new Image();
  img.onload = () => {
    // 1:1 (exact overlay colours) when the frame fits the 640 x 480 panel, else scaled down.
    const k = Math.min(1, 640 / img.width, 480 / img.height);
    const w = Math.round(img.width * k), h = Math.round(img.height * k);
    if (camCanvas.width !== w || camCanvas.height !== h) { camCanvas.width = w; camCanvas.height = h; }
    cctx.imageSmoothingEnabled = k < 1;
    cctx.drawImage(img, 0, 0, w, h);
    setTimeout(loadFrame, 250);
  };
  img.onerror = () => setTimeout(loadFrame, 1000);
  img.src = '/frame.jpg?n=' + Date.now();
}

drawField();
loadField();
poll();
loadFrame();
</script>
</body>
</html>
)HTML";

}  // namespace

std::string_view LiveState::page_html() {
  return kPage;
}

}  // namespace omniloc::live
