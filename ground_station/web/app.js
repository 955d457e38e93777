// alight ground station page: polls /api/state, pulls video frames from /api/frame/*, plots the
// mission like the paper's Figs. 10 (top-down) and 11 (height over time), and posts commands
// (buttons, keyboard, Gamepad API). The server signs commands; the page only asks for them.
'use strict';

const $ = (id) => document.getElementById(id);
const MISSIONS = { 0: 'none', 1: 'landing', 2: 'ingress' };
const FAILSAFES = {
  0: 'none', 1: 'pose stale', 2: 'pose lost', 3: 'operator abort', 4: 'kill', 5: 'estimate lost',
};
const NUDGE_STEP_M = 0.1;

let latest = null;          // newest state document
let station = {};           // the server's "station" part
// Every command carries the session token in X-Alight-Token (a header a cross-site form cannot
// send). It comes from the URL fragment, the station (loopback only: GET /api/session), or the
// operator typing it.
let token = (() => {
  const m = /token=([0-9a-fA-F]+)/.exec(location.hash);
  return m ? m[1] : '';
})();
async function fetchSessionToken() {
  if (token) return;
  try {
    const r = await fetch('/api/session', { cache: 'no-store' });
    const j = await r.json();
    if (j.ok && j.token) token = j.token;
  } catch (e) { /* typed in by the operator instead */ }
}

const fmt = (v, d = 2) => (v === null || v === undefined || Number.isNaN(v)) ? '—' : Number(v).toFixed(d);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// ---- video: one request per frame, each waiting server-side for a newer frame --------------
function startVideo(name) {
  const img = $('video-' + name);
  const stats = $('stats-' + name);
  const arrivals = [];
  let seq = 0;
  let lastUtime = 0;
  let url = null;
  (async function loop() {
    for (;;) {
      try {
        const r = await fetch(`/api/frame/${name}?after=${seq}`, { cache: 'no-store' });
        if (r.status !== 200) { await sleep(200); continue; }
        const s = Number(r.headers.get('X-Frame-Seq'));
        const blob = await r.blob();
        if (s === seq) continue;
        seq = s;
        lastUtime = Number(r.headers.get('X-Frame-Utime'));
        const next = URL.createObjectURL(blob);
        img.src = next;
        if (url) URL.revokeObjectURL(url);
        url = next;
        img.dataset.seq = String(seq);
        const now = performance.now();
        arrivals.push(now);
        while (arrivals.length && arrivals[0] < now - 2000) arrivals.shift();
      } catch (e) {
        await sleep(1000);  // server gone or restarting
      }
    }
  })();
  setInterval(() => {
    const now = performance.now();
    while (arrivals.length && arrivals[0] < now - 2000) arrivals.shift();
    const fps = arrivals.length > 1 ? (arrivals.length - 1) / ((now - arrivals[0]) / 1000) : 0;
    const age = lastUtime ? (Date.now() * 1000 - lastUtime) / 1e6 : NaN;
    stats.textContent = seq ? `${fps.toFixed(1)} fps · age ${fmt(age, 2)} s · #${seq}` : 'no frames';
    stats.dataset.fps = fps.toFixed(2);
  }, 500);
}

// ---- commands ------------------------------------------------------------------------------
async function sendCommand(command, extra = {}) {
  const body = new URLSearchParams({ command, ...extra });
  if (command === 'go') body.set('mission', $('mission-select').value);
  const headers = { 'Content-Type': 'application/x-www-form-urlencoded' };
  const t = token || $('token').value.trim();
  if (t) headers['X-Alight-Token'] = t;
  const out = $('cmd-result');
  try {
    const r = await fetch('/api/command', { method: 'POST', headers, body });
    const j = await r.json();
    if (j.ok) {
      out.textContent = `sent ${j.command} (seq ${j.seq})`;
      out.className = 'cmd-result ok';
    } else {
      out.textContent = `refused: ${j.error}`;
      out.className = 'cmd-result bad';
    }
  } catch (e) {
    out.textContent = `failed: ${e}`;
    out.className = 'cmd-result bad';
  }
}

function nudge(dx, dy, dz) {
  return sendCommand('nudge', {
    dx: (dx * NUDGE_STEP_M).toFixed(3), dy: (dy * NUDGE_STEP_M).toFixed(3),
    dz: (dz * NUDGE_STEP_M).toFixed(3),
  });
}

function askKill() { $('kill-dialog').hidden = false; $('kill-cancel').focus(); }
function closeKill() { $('kill-dialog').hidden = true; }
function confirmKill() { closeKill(); sendCommand('kill', { confirm: 'kill' }); }

function setupControls() {
  for (const b of document.querySelectorAll('button[data-cmd]'))
    b.addEventListener('click', () => sendCommand(b.dataset.cmd));
  for (const b of document.querySelectorAll('button[data-nudge]')) {
    const [x, y, z] = b.dataset.nudge.split(',').map(Number);
    b.addEventListener('click', () => nudge(x, y, z));
  }
  $('btn-kill').addEventListener('click', askKill);
  $('kill-confirm').addEventListener('click', confirmKill);
  $('kill-cancel').addEventListener('click', closeKill);
  $('nudge-step').textContent = NUDGE_STEP_M.toFixed(2);

  document.addEventListener('keydown', (e) => {
    if (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT') return;
    const killOpen = !$('kill-dialog').hidden;
    if (killOpen) {
      if (e.key === 'K' && e.shiftKey) confirmKill();
      else if (e.key === 'Escape') closeKill();
      e.preventDefault();
      return;
    }
    const keys = {
      t: () => sendCommand('takeoff'), g: () => sendCommand('go'), a: () => sendCommand('abort'),
      Escape: () => sendCommand('abort'), l: () => sendCommand('land_here'), k: askKill,
      ArrowUp: () => nudge(1, 0, 0), ArrowDown: () => nudge(-1, 0, 0),
      ArrowLeft: () => nudge(0, 1, 0), ArrowRight: () => nudge(0, -1, 0),
      PageUp: () => nudge(0, 0, 1), PageDown: () => nudge(0, 0, -1),
      1: () => { $('mission-select').value = 'landing'; },
      2: () => { $('mission-select').value = 'ingress'; },
    };
    const fn = keys[e.key];
    if (fn && !e.repeat && !e.ctrlKey && !e.altKey && !e.metaKey) { e.preventDefault(); fn(); }
  });
}

// ---- gamepad (standard mapping): left stick x/y and right stick y nudge at 5 Hz; A go,
// B abort, X land here, Y take off; LB+RB held 1 s asks to kill, then A confirms, B cancels.
function setupGamepad() {
  let pressed = null;  // button states at the previous poll; null until a pad is first seen
  let lastNudge = 0;
  let killHoldSince = null;
  const edge = (pad, i) => {
    const down = pad.buttons[i] && pad.buttons[i].pressed;
    const was = pressed[i];
    pressed[i] = down;
    return down && !was;
  };
  const dead = (v) => (Math.abs(v) < 0.2 ? 0 : v);
  function poll(ts) {
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    const pad = Array.from(pads).find((p) => p && p.connected);
    // A button already held when the pad appears (or the page loads) must not fire.
    if (pad && !pressed) pressed = pad.buttons.map((b) => b.pressed);
    if (pad) {
      $('gamepad').textContent = `gamepad: ${pad.id.slice(0, 40)}`;
      const killOpen = !$('kill-dialog').hidden;
      if (killOpen) {
        if (edge(pad, 0)) confirmKill();
        if (edge(pad, 1)) closeKill();
      } else {
        if (edge(pad, 0)) sendCommand('go');
        if (edge(pad, 1)) sendCommand('abort');
        if (edge(pad, 2)) sendCommand('land_here');
        if (edge(pad, 3)) sendCommand('takeoff');
        const both = pad.buttons[4] && pad.buttons[5] && pad.buttons[4].pressed && pad.buttons[5].pressed;
        if (both) {
          if (killHoldSince === null) killHoldSince = ts;
          else if (ts - killHoldSince > 1000) { killHoldSince = Infinity; askKill(); }
        } else {
          killHoldSince = null;
        }
        const dx = -dead(pad.axes[1] || 0), dy = -dead(pad.axes[0] || 0), dz = -dead(pad.axes[3] || 0);
        if ((dx || dy || dz) && ts - lastNudge > 200) { lastNudge = ts; nudge(dx, dy, dz); }
      }
    }
    requestAnimationFrame(poll);
  }
  window.addEventListener('gamepadconnected', (e) => { $('gamepad').textContent = `gamepad: ${e.gamepad.id}`; });
  requestAnimationFrame(poll);
}

// ---- plots ---------------------------------------------------------------------------------
function series(flat, stride) {
  const out = [];
  for (let i = 0; i + stride <= flat.length; i += stride) out.push(flat.slice(i, i + stride));
  return out;
}

// Top-down view like the paper's Fig. 10: world x up, y to the left (REP-103 seen from above).
function drawTop(s) {
  const c = $('plot-top');
  const g = c.getContext('2d');
  g.fillStyle = '#0d1014';
  g.fillRect(0, 0, c.width, c.height);
  const track = series(s.track || [], 4);
  const meas = series(s.measurements || [], 4);
  const st = typeof s.status === 'object' ? s.status : null;
  const pts = [];
  for (const p of track) pts.push([p[1], p[2]]);
  for (const m of meas) pts.push([m[1], m[2]]);
  if (st && st.has_estimate) pts.push([st.estimate_W[0], st.estimate_W[1]]);
  if (st) pts.push([st.setpoint_W[0], st.setpoint_W[1]]);
  if (!pts.length) pts.push([0, 0]);
  let xmin = Math.min(...pts.map((p) => p[0])), xmax = Math.max(...pts.map((p) => p[0]));
  let ymin = Math.min(...pts.map((p) => p[1])), ymax = Math.max(...pts.map((p) => p[1]));
  const span = Math.max(xmax - xmin, ymax - ymin, 2) * 1.2;
  const cx = (xmin + xmax) / 2, cy = (ymin + ymax) / 2;
  const scale = Math.min(c.width, c.height) / span;  // px per metre
  const px = (x, y) => [c.width / 2 - (y - cy) * scale, c.height / 2 - (x - cx) * scale];
  // 1 m grid
  g.strokeStyle = '#1f262e';
  g.lineWidth = 1;
  const half = span;
  for (let v = Math.floor(cx - half); v <= cx + half; v++) {
    const [, yy] = px(v, cy);
    g.beginPath(); g.moveTo(0, yy); g.lineTo(c.width, yy); g.stroke();
  }
  for (let v = Math.floor(cy - half); v <= cy + half; v++) {
    const [xx] = px(cx, v);
    g.beginPath(); g.moveTo(xx, 0); g.lineTo(xx, c.height); g.stroke();
  }
  // track
  g.strokeStyle = '#58a6ff';
  g.lineWidth = 1.5;
  g.beginPath();
  track.forEach((p, i) => { const [a, b] = px(p[1], p[2]); if (i) g.lineTo(a, b); else g.moveTo(a, b); });
  g.stroke();
  // waypoint measurements
  g.fillStyle = '#d29922';
  for (const m of meas) { const [a, b] = px(m[1], m[2]); g.fillRect(a - 1.5, b - 1.5, 3, 3); }
  // estimate with 1- and 2-sigma ellipses of its xy covariance
  if (st && st.has_estimate) {
    const [ex, ey] = px(st.estimate_W[0], st.estimate_W[1]);
    const cxx = st.covariance[0], cxy = st.covariance[1], cyy = st.covariance[4];
    const tr = (cxx + cyy) / 2, det = Math.sqrt(Math.max(0, ((cxx - cyy) / 2) ** 2 + cxy * cxy));
    const l1 = tr + det, l2 = Math.max(0, tr - det);
    const ang = 0.5 * Math.atan2(2 * cxy, cxx - cyy);  // major axis angle from world x
    g.strokeStyle = '#3fb950';
    for (const k of [1, 2]) {
      g.beginPath();
      // canvas rotation: world x is up (-canvas y), world y is left (-canvas x)
      g.ellipse(ex, ey, Math.sqrt(l2) * k * scale, Math.sqrt(l1) * k * scale, -ang, 0, 2 * Math.PI);
      g.stroke();
    }
    g.beginPath(); g.moveTo(ex - 7, ey); g.lineTo(ex + 7, ey); g.moveTo(ex, ey - 7); g.lineTo(ex, ey + 7);
    g.lineWidth = 2; g.stroke();
  }
  if (st) {
    const [sx, sy] = px(st.setpoint_W[0], st.setpoint_W[1]);
    g.strokeStyle = '#f0f'; g.lineWidth = 1.5;
    g.beginPath(); g.arc(sx, sy, 5, 0, 2 * Math.PI); g.stroke();
  }
  if (typeof s.pose === 'object') {
    const [vx, vy] = px(s.pose.p_W[0], s.pose.p_W[1]);
    g.fillStyle = '#e6e8eb';
    g.beginPath(); g.arc(vx, vy, 4, 0, 2 * Math.PI); g.fill();
  }
  g.fillStyle = '#8a93a0';
  g.font = '11px sans-serif';
  g.fillText(`grid 1 m · view ${span.toFixed(1)} m`, 6, c.height - 6);
}

// Height over time like the paper's Fig. 11.
function drawHeight(s) {
  const c = $('plot-height');
  const g = c.getContext('2d');
  g.fillStyle = '#0d1014';
  g.fillRect(0, 0, c.width, c.height);
  const h = series(s.heights || [], 4);
  if (h.length < 2) return;
  const t0 = h[0][0], t1 = h[h.length - 1][0];
  const zs = [];
  for (const p of h) {
    if (p[1] !== null) zs.push(p[1]);
    if (p[2] !== null) { zs.push(p[2] - 2 * (p[3] || 0)); zs.push(p[2] + 2 * (p[3] || 0)); }
  }
  let zmin = Math.min(0, ...zs), zmax = Math.max(1, ...zs);
  const pad = 28;
  const X = (t) => pad + (t - t0) / Math.max(t1 - t0, 1e-3) * (c.width - pad - 6);
  const Y = (z) => c.height - 16 - (z - zmin) / (zmax - zmin) * (c.height - 24);
  g.strokeStyle = '#1f262e';
  g.fillStyle = '#8a93a0';
  g.font = '10px sans-serif';
  for (let z = Math.ceil(zmin); z <= zmax; z++) {
    g.beginPath(); g.moveTo(pad, Y(z)); g.lineTo(c.width, Y(z)); g.stroke();
    g.fillText(`${z} m`, 2, Y(z) + 3);
  }
  g.fillText(`${(t1 - t0).toFixed(0)} s`, c.width - 30, c.height - 3);
  g.fillStyle = '#58a6ff';
  g.fillText('vehicle z', pad + 4, 12);
  g.fillStyle = '#3fb950';
  g.fillText('estimate z ± 2σ', pad + 64, 12);
  // estimate band and line
  const est = h.filter((p) => p[2] !== null);
  if (est.length) {
    g.fillStyle = 'rgba(63,185,80,0.25)';
    g.beginPath();
    est.forEach((p, i) => { const a = X(p[0]), b = Y(p[2] + 2 * (p[3] || 0)); if (i) g.lineTo(a, b); else g.moveTo(a, b); });
    for (let i = est.length - 1; i >= 0; i--) g.lineTo(X(est[i][0]), Y(est[i][2] - 2 * (est[i][3] || 0)));
    g.closePath(); g.fill();
    g.strokeStyle = '#3fb950'; g.lineWidth = 1.5;
    g.beginPath();
    est.forEach((p, i) => { if (i) g.lineTo(X(p[0]), Y(p[2])); else g.moveTo(X(p[0]), Y(p[2])); });
    g.stroke();
  }
  g.strokeStyle = '#58a6ff'; g.lineWidth = 1.5;
  g.beginPath();
  let started = false;
  for (const p of h) {
    if (p[1] === null) continue;
    if (started) g.lineTo(X(p[0]), Y(p[1])); else { g.moveTo(X(p[0]), Y(p[1])); started = true; }
  }
  g.stroke();
}

// ---- state ---------------------------------------------------------------------------------
function rows(tbody, list) {
  tbody.innerHTML = '';
  for (const { cells, cls } of list) {
    const tr = document.createElement('tr');
    if (cls) tr.className = cls;
    for (const c of cells) {
      const td = document.createElement('td');
      if (typeof c === 'object') { td.textContent = c.text; td.className = c.cls; } else td.textContent = c;
      tr.appendChild(td);
    }
    tbody.appendChild(tr);
  }
}

function render(s) {
  station = s.station || {};
  const st = typeof s.status === 'object' ? s.status : null;
  $('phase').textContent = st ? st.phase_name : '—';
  $('phase').dataset.phase = st ? String(st.phase) : '';
  $('mission').textContent = st ? MISSIONS[st.mission] || st.mission : '—';
  $('n-meas').textContent = st ? `${st.n_measurements} (rej ${st.n_rejected})` : '—';
  $('failsafe').textContent = st ? FAILSAFES[st.failsafe] || st.failsafe : '—';
  $('mission-time').textContent = st ? `${fmt(st.mission_time_s, 1)} s` : '—';
  const byReason = st && st.cmds_rejected_by_reason ? Object.entries(st.cmds_rejected_by_reason)
    .map(([why, n]) => `${n} ${why}`).join(', ') : '';
  $('reason').textContent = st ? (st.reason || '') + (st.cmds_rejected
    ? ` · ${st.cmds_rejected} cmds rejected${byReason ? ` (${byReason})` : ''}` : '') : '—';

  const ch = s.channels || {};
  const statusCh = ch[station.status_channel];
  const link = $('link');
  if (!statusCh) { link.textContent = 'no link'; link.className = 'link bad'; }
  else if (statusCh.stale) { link.textContent = `link stale ${fmt(statusCh.age_s, 1)} s`; link.className = 'link bad'; }
  else if (statusCh.age_s > 0.3) { link.textContent = `link slow ${fmt(statusCh.age_s, 2)} s`; link.className = 'link warn'; }
  else { link.textContent = `link ok ${fmt(statusCh.rate_hz, 0)} Hz`; link.className = 'link ok'; }

  rows($('channels').tBodies[0], Object.entries(ch).map(([name, c]) => ({
    cells: [name, `${fmt(c.rate_hz, 1)} Hz`, `${fmt(c.age_s, 2)} s`, c.count], cls: c.stale ? 'stale' : '',
  })));

  const t = typeof s.target === 'object' ? s.target : null;
  rows($('target').tBodies[0], t ? [
    { cells: ['found', t.found ? 'yes' : `no (${t.reason})`] },
    { cells: ['p_W_target', t.p_W_target.map((v) => fmt(v)).join(', ') + ' m'] },
    { cells: ['height', `${fmt(t.target_height_m)} m`] },
    { cells: ['size', `${fmt(t.size_m[0])} × ${fmt(t.size_m[1])} m`] },
    { cells: ['baseline', `${fmt(t.baseline_m)} m`] },
    { cells: ['features / matches', `${t.n_features} / ${t.n_matches}`] },
    { cells: ['inliers dom / target', `${t.n_inliers_dominant} / ${t.n_inliers_target}`] },
  ] : [{ cells: ['no VISION_TARGET yet'] }]);
  // Every target's reason counted since the start: which gate refuses the frames, most first.
  const reasons = s.target_reasons && typeof s.target_reasons === 'object'
    ? Object.entries(s.target_reasons).sort((a, b) => b[1] - a[1]) : [];
  rows($('target-reasons').tBodies[0], reasons.map(([name, n]) => ({ cells: [name, n] })));

  // The autopilot over MAVLink (alight-mavlink), on a real vehicle.
  const ap = typeof s.autopilot === 'object' ? s.autopilot : null;
  $('autopilot-name').textContent = ap ? `(${ap.autopilot})` : '';
  rows($('autopilot').tBodies[0], ap ? [
    { cells: ['link', ap.link_up ? `up, heartbeat ${fmt(ap.heartbeat_age_s, 1)} s` : 'DOWN'],
      cls: ap.link_up ? '' : 'stale' },
    { cells: ['firmware', ap.firmware ? `${ap.firmware}${ap.accel_feedforward ? ', takes acceleration' : ''}` : 'not known yet'] },
    { cells: ['mode', `${ap.mode || '?'}${ap.offboard ? ' (alight flies)' : ''}`] },
    { cells: ['armed', ap.armed ? 'ARMED' : 'disarmed'] },
    { cells: ['bridge', `${ap.engage}${ap.streaming ? ', streaming' : ''}`],
      cls: ap.engage === 'OVERRIDE' ? 'stale' : '' },
    { cells: ['last command', ap.last_command ? `${ap.last_command}: ${
      ap.last_result === 0 ? 'accepted' : ap.last_result === -1 ? 'no answer' : `result ${ap.last_result}`}` : '–'] },
    { cells: ['autopilot says', ap.last_statustext || '–'] },
    { cells: ['battery', ap.battery_V >= 0 ? `${fmt(ap.battery_V, 2)} V` : '–'] },
  ] : [{ cells: ['no AUTOPILOT_STATUS (simulated autopilot over LCM)'] }]);

  // Every node's refusals for a message's origin: unsigned or forged on a signed bus, replayed,
  // or a second publisher on a channel. Any of them is an alarm.
  const bus = typeof s.bus === 'object' ? s.bus : null;
  const alarmEl = $('bus-alarm');
  alarmEl.textContent = bus && bus.alarm ? 'ALARM: messages refused for their origin' : '';
  alarmEl.className = bus && bus.alarm ? 'alarm' : '';
  rows($('bus').tBodies[0], bus && bus.nodes.length ? bus.nodes.map((n) => ({
    cells: [n.node, n.signed ? 'signed' : { text: 'UNSIGNED', cls: 'alarm' },
      n.refused.length ? { text: n.refused.map((c) =>
        `${c.channel}: ${c.rejected_auth} forged/unsigned, ${c.second_publisher} second publisher`)
        .join('; '), cls: 'alarm' } : '–'],
  })) : [{ cells: ['no NODE_STATUS'] }]);

  const p = typeof s.processes === 'object' ? s.processes : null;
  $('launch-name').textContent = p ? `(${p.launch_name})` : '';
  rows($('processes').tBodies[0], p ? p.list.map((q) => ({
    cells: [q.name, { text: q.state, cls: 'state-' + q.state }, q.pid, q.restarts,
      q.signal ? `sig ${q.signal}` : q.exit_code],
  })) : [{ cells: ['no PROCESS_STATUS'] }]);

  // Each command: sent, then acknowledged (AUTONOMY_STATUS echoed it), rejected (with the
  // vehicle's reason), or NOT ACKNOWLEDGED once the deadline passed without an answer.
  const ACK_TEXT = {
    sent: () => 'sent',
    acknowledged: (c) => `acknowledged ${fmt(c.answer_s, 2)} s`,
    rejected: (c) => `REJECTED: ${c.reject_reason}`,
    not_acknowledged: () => 'NOT ACKNOWLEDGED',
  };
  rows($('sent').tBodies[0], (s.sent || []).slice(-6).reverse().map((c) => ({
    cells: [c.name, `seq …${String(c.seq).slice(-6)}`,
      { text: (ACK_TEXT[c.state] || (() => c.state))(c), cls: 'ack-' + c.state },
      `${fmt(c.age_s, 1)} s ago`],
  })));
  const lk = typeof s.link === 'object' ? s.link : {};
  const alarm = $('ack-alarm');
  if (lk.alarm && typeof lk.alarm === 'object') {
    alarm.hidden = false;
    alarm.textContent = `${lk.alarm.name.toUpperCase()} NOT ACKNOWLEDGED by ${lk.vehicle_id} ` +
      `(${fmt(lk.alarm.age_s, 1)} s, seq …${String(lk.alarm.seq).slice(-6)}): do not assume it acted`;
  } else {
    alarm.hidden = true;
  }
  const off = $('clock-offset');
  if (lk.clock_offset_s === null || lk.clock_offset_s === undefined) {
    off.textContent = 'clock offset —';
    off.className = 'link';
  } else {
    off.textContent = `clock offset ${lk.clock_offset_s >= 0 ? '+' : ''}${fmt(lk.clock_offset_s, 3)} s`;
    off.className = lk.clock_offset_warn ? 'link bad' : 'link ok';
  }
  if (lk.vehicle_seen && !lk.session_known) {
    $('cmd-result').textContent = lk.other_vehicle_id
      ? `vehicle '${lk.other_vehicle_id}' heard, but this station commands '${lk.vehicle_id}'`
      : `vehicle '${lk.vehicle_id}' announces no command session (no key there?)`;
    $('cmd-result').className = 'cmd-result bad';
  }

  const enabled = !!station.commands_enabled;
  for (const b of document.querySelectorAll('.controls button')) b.disabled = !enabled;
  if (!enabled) $('cmd-result').textContent = 'view-only (ground station started without --key-file)';
  $('token-row').hidden = !(station.token_required && !token);

  drawTop(s);
  drawHeight(s);
}

async function pollState() {
  for (;;) {
    try {
      const r = await fetch('/api/state', { cache: 'no-store' });
      latest = await r.json();
      render(latest);
    } catch (e) {
      const link = $('link');
      link.textContent = 'ground station unreachable';
      link.className = 'link bad';
    }
    await sleep(250);
  }
}

fetchSessionToken();
setupControls();
setupGamepad();
startVideo('camera');
startVideo('diag');
pollState();
