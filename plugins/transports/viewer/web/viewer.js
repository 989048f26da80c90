// SPDX-License-Identifier: Apache-2.0
// viewer.js: the WebSocket link to the ÜberSim server, drawing of the latest state, toolbar,
// status bar, keyboard and pointer gestures. Geometry and the field layer live in field.js, the
// match (scoreboard, placement target) in match.js, a replayed log's time slider in replay.js.
// Frames are drawn on requestAnimationFrame only when a new state arrived or the user acted.
'use strict';
(function () {
  const F = window.UberSimField;
  const M = window.UberSimMatch;
  const R = window.UberSimReplay;
  const $ = (id) => document.getElementById(id);
  const canvas = $('field');
  const ctx = canvas.getContext('2d');

  const TRAIL_SECONDS = 1.5;   // s of sim time kept in a trail
  const TRAIL_MIN_DT = 0.02;   // s of sim time between kept trail points
  const TRAIL_RUN = 6;         // segments per stroke: the fade steps without one stroke per segment
  const MOVE_INTERVAL = 50;    // ms: drag moves go out at ~20 Hz
  const KICK_GAIN = 2;         // (m/s) per metre of drag
  const KICK_MAX = 6.5;        // m/s, the rules' limit
  const HIT_PX = 10;           // CSS px: smallest grab radius (touch gets twice that)
  const ROTATE_STEP = Math.PI / 18;  // rad per wheel notch or q/e press
  const SETTLE_MS = 500;       // after a drag, hold the object at its drop point this long at most
  const TEAM_FILL = { blue: '#2c6cff', yellow: '#ffd51c' };
  const TEAM_TEXT = { blue: '#ffffff', yellow: '#111111' };
  const TEAM_LINE = { blue: '#8fb4ff', yellow: '#fff07a' };  // detections: lighter, on green
  const BALL_FILL = '#ff8a1f';
  const CONTACT = '#ff3df0';

  const view = new F.View();
  let field = F.normalize(null);
  let fieldLayer = null;
  let layerDirty = true;
  let dpr = 1;

  const api = {
    connected: false, hello: null, state: null, referee: null, drawn: null, frames: 0, selected: null,
    fieldToClient, clientToField, send,
    render: () => requestRender(),
  };
  window.ubersimViewer = api;

  // ---------------------------------------------------------------- connection

  let ws = null;
  let nextId = 1;
  let everConnected = false;

  function connect() {
    let sock;
    try {
      sock = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
    } catch (e) {
      setTimeout(connect, 1000);
      return;
    }
    ws = sock;
    sock.onopen = () => {
      api.connected = true;
      api.referee = null;  // the server sends its latest right after the hello
      everConnected = true;
      setConnection('connected', true);
      requestRender();
    };
    sock.onmessage = (ev) => { if (typeof ev.data === 'string') onMessage(ev.data); };
    sock.onclose = () => {
      if (ws !== sock) return;
      ws = null;
      api.connected = false;
      setConnection('disconnected', false);
      setText('run-state', '–');  // the last status is stale now
      $('run-state').className = '';
      requestRender();
      setTimeout(connect, 1000);
    };
  }

  function setConnection(text, good) {
    const el = $('connection');
    el.textContent = text;
    el.className = good ? 'good' : 'bad';
  }

  function send(obj) {
    if (!ws || ws.readyState !== WebSocket.OPEN) {
      showError('not connected');
      return null;
    }
    const msg = Object.assign({}, obj);
    if (msg.id === undefined) msg.id = nextId++;
    ws.send(JSON.stringify(msg));
    return msg.id;
  }

  function onMessage(text) {
    let m;
    try { m = JSON.parse(text); } catch (e) { return; }
    if (!m || typeof m !== 'object') return;
    if (m.type === 'hello') onHello(m);
    else if (m.type === 'state') onState(m);
    else if (m.type === 'referee') onReferee(m);
    else if (m.type === 'error') showError(`${m.cmd || 'command'}: ${m.message || 'failed'}`);
  }

  let cameras = [];
  function onHello(m) {
    api.hello = m;
    field = F.normalize(m.field);
    cameras = Array.isArray(m.cameras) ? m.cameras : [];
    layerDirty = true;
    trails.clear();
    lastSig = '';
    $('world').textContent = m.world ? String(m.world) : '';
    R.hello(m);
    M.update(m, api.referee, api.state && api.state.status);
    requestRender();
  }

  function onReferee(m) {
    api.referee = m.cleared ? null : m;  // a replay gone back to before the first Referee message
    M.update(api.hello, m, api.state && api.state.status);
    requestRender();  // the placement target
  }

  let lastSig = '';
  function onState(s) {
    api.state = s;
    recordTrails(s);
    updateStatus(s);
    R.state(s);
    updatePanel(s);
    M.update(api.hello, api.referee, s.status);  // the hint: how long the referee has been silent
    // A paused simulation keeps sending the same state: redraw only when something moved.
    const frames = Array.isArray(s.vision) ? s.vision.map((v) => v && v.frame) : [];
    const sig = `${s.step}|${JSON.stringify(s.ball)}|${JSON.stringify(s.robots)}|${frames}`;
    if (sig !== lastSig) {
      lastSig = sig;
      requestRender();
    }
  }

  // ---------------------------------------------------------------- status bar and toolbar

  function setText(id, text) {
    const el = $(id);
    if (el.textContent !== text) el.textContent = text;
  }

  let pending = null;        // {paused, until}: the state asked for, until the server shows it
  let lastSpeed;             // status.speed last mirrored into the select
  function statusPaused() { return !!(api.state && api.state.status && api.state.status.paused); }
  function effectivePaused() {
    const p = statusPaused();
    if (pending && (p === pending.paused || performance.now() > pending.until)) pending = null;
    return pending ? pending.paused : p;
  }

  function updateStatus(s) {
    const st = s.status && typeof s.status === 'object' ? s.status : {};
    setText('sim-time', Number.isFinite(s.t) ? `${s.t.toFixed(3)} s` : '–');
    setText('rtf', Number.isFinite(st.rtf) ? `${st.rtf.toFixed(2)}×` : '–');
    setText('vision-rate', Number.isFinite(st.vision_hz)
      ? `${st.vision_hz.toFixed(1)} Hz · ${Number.isFinite(st.cameras) ? st.cameras : 0} cam` : '–');
    setText('clients', Number.isFinite(st.clients) ? String(st.clients) : '–');
    const paused = effectivePaused();
    setText('run-state', statusPaused() ? 'paused' : 'running');
    $('run-state').className = statusPaused() ? 'paused' : '';
    setText('pause', paused ? 'Resume' : 'Pause');
    // Mirror the server's speed, but never while the user is choosing one.
    const speed = Number.isFinite(st.speed) ? st.speed : null;
    const sel = $('speed');
    if (speed !== lastSpeed && document.activeElement !== sel) {
      lastSpeed = speed;
      const v = speed === null ? '' : String(speed);
      sel.value = [...sel.options].some((o) => o.value === v) ? v : '';
    }
  }

  let errorTimer = 0;
  function showError(text) {
    const el = $('last-error');
    el.textContent = `error: ${text}`;
    el.classList.remove('old');
    clearTimeout(errorTimer);
    errorTimer = setTimeout(() => el.classList.add('old'), 6000);  // stays as "last error", dimmed
  }

  // ---------------------------------------------------------------- robot panel

  // A clicked robot's truth and what its drive measured of itself (Drive::Feedback): what the
  // robot's own firmware would report, beside what is really there.
  let selected = null;  // robotKey of the robot shown in the panel, or null
  // Values that round to zero read 0, not -0.
  const fmt = (v, digits) => (Number.isFinite(v) ? (Math.abs(v) < 0.5 * 10 ** -digits ? 0 : v).toFixed(digits) : '–');
  const deg = (rad) => (Number.isFinite(rad) ? (rad * 180 / Math.PI).toFixed(1) : '–');

  function select(key) {
    selected = key;
    api.selected = key;
    if (api.state) updatePanel(api.state);
    requestRender();
  }

  // A replay knows only where the cameras saw the robot, and which did.
  function replayRows(r) {
    const seen = [];
    for (const f of api.state && Array.isArray(api.state.vision) ? api.state.vision : []) {
      if (f && Array.isArray(f.robots) && f.robots.some((d) => d && robotKey(d) === robotKey(r))) seen.push(f.camera);
    }
    return [
      ['position', `${fmt(r.x, 3)}, ${fmt(r.y, 3)} m`],
      ['heading', `${deg(r.yaw)}°`],
      ['seen by', seen.length ? `camera ${seen.join(', ')}` : '–'],
    ];
  }

  function panelRows(r) {
    if (R.active()) return replayRows(r);
    const rows = [
      ['position', `${fmt(r.x, 3)}, ${fmt(r.y, 3)} m`],
      ['heading', `${deg(r.yaw)}°`],
      ['velocity', `${fmt(r.vx, 2)}, ${fmt(r.vy, 2)} m/s · ${fmt(r.w, 2)} rad/s`],
      ['dribbler', r.contact ? 'touches the ball' : 'no contact'],
      ['kicker', r.kicker_ready ? 'charged' : 'not charged'],
    ];
    const d = r.drive;
    if (d && typeof d === 'object') {
      rows.push(['drive says', `${fmt(d.forward, 2)} fwd, ${fmt(d.left, 2)} left m/s · ${fmt(d.angular, 2)} rad/s`]);
      const wheels = Array.isArray(d.wheels) ? d.wheels : [];
      wheels.forEach((w, i) => rows.push([`wheel ${i + 1}`, `${fmt(w, 1)} rad/s`]));
    } else {
      rows.push(['drive says', 'nothing (no working drive)']);
    }
    return rows;
  }

  function updatePanel(s) {
    const panel = $('robot-panel');
    const robots = Array.isArray(s.robots) ? s.robots : [];
    const r = selected ? robots.find((o) => o && robotKey(o) === selected && o.present !== false) : null;
    if (!r) {
      if (!panel.hidden) panel.hidden = true;
      return;
    }
    setText('robot-panel-title', `${r.team} ${r.id}`);
    const body = $('robot-panel-rows');
    const rows = panelRows(r);
    while (body.rows.length > rows.length) body.deleteRow(-1);
    rows.forEach(([name, value], i) => {
      const row = body.rows[i] || body.insertRow();
      if (row.cells.length === 0) { row.insertCell(); row.insertCell(); }
      if (row.cells[0].textContent !== name) row.cells[0].textContent = name;
      if (row.cells[1].textContent !== value) row.cells[1].textContent = value;
    });
    if (panel.hidden) panel.hidden = false;
  }

  $('robot-panel-close').addEventListener('click', (e) => { select(null); e.currentTarget.blur(); });

  function togglePause() {
    const p = effectivePaused();
    if (send({ cmd: p ? 'resume' : 'pause' }) === null) return;
    pending = { paused: !p, until: performance.now() + 2000 };
    setText('pause', p ? 'Pause' : 'Resume');
  }

  function stepCount() {
    const dt = api.state && api.state.step_dt > 0 ? api.state.step_dt : 0.001;
    const v = $('step-size').value;
    const n = v === 'step' ? 1 : Math.round((v === 'frame' ? 1 / 60 : Number(v)) / dt);
    return Math.min(100000, Math.max(1, n || 1));
  }
  function doStep() { send({ cmd: 'step', steps: stepCount() }); }
  function doReset() {
    if (send({ cmd: 'reset' }) !== null) trails.clear();
  }

  // Buttons give their focus back so space/r keep acting on the viewer, not the last button.
  const clickOf = (id, fn) => $(id).addEventListener('click', (e) => { fn(); e.currentTarget.blur(); });
  clickOf('pause', togglePause);
  clickOf('step', doStep);
  clickOf('reset', doReset);
  $('speed').addEventListener('change', (e) => {
    if (e.target.value !== '') send({ cmd: 'speed', factor: Number(e.target.value) });
    e.target.blur();
  });
  $('step-size').addEventListener('change', (e) => e.target.blur());
  for (const id of ['trails', 'cameras']) $(id).addEventListener('change', requestRender);

  const isToggle = (el) => el && (el.tagName === 'BUTTON' || el.tagName === 'SUMMARY'
    || (el.tagName === 'INPUT' && el.type === 'checkbox'));
  window.addEventListener('keydown', (e) => {
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    const el = e.target;
    if (el && (el.tagName === 'SELECT' || el.tagName === 'TEXTAREA'
      || (el.tagName === 'INPUT' && el.type !== 'checkbox'))) return;
    const k = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    if (R.active()) {  // a replay: play/pause and skip; nothing changes a world
      if (k === ' ') {
        if (isToggle(el)) el.blur();
        if (!e.repeat) R.togglePlay();
      } else if (k === 'ArrowLeft' || k === 'ArrowRight') {
        R.skip(k === 'ArrowLeft' ? -5 : 5);
      } else {
        return;
      }
      e.preventDefault();
      return;
    }
    if (drag && drag.kind === 'robot' && (k === 'q' || k === 'e')) {
      rotateDrag(k === 'q' ? ROTATE_STEP : -ROTATE_STEP);
    } else if (k === ' ') {
      if (isToggle(el)) el.blur();  // else the focused control would toggle too
      if (!e.repeat) togglePause();
    } else if (k === '.' || k === 's') {
      doStep();
    } else if (k === 'r') {
      if (!e.repeat) doReset();
    } else {
      return;
    }
    e.preventDefault();
  });
  window.addEventListener('keyup', (e) => { if (e.key === ' ' && isToggle(e.target)) e.preventDefault(); });

  // ---------------------------------------------------------------- geometry helpers

  function ensureSize() {
    const w = canvas.clientWidth, h = canvas.clientHeight, r = window.devicePixelRatio || 1;
    const W = Math.max(1, Math.round(w * r)), H = Math.max(1, Math.round(h * r));
    if (W !== canvas.width || H !== canvas.height || r !== dpr || layerDirty || !fieldLayer) {
      dpr = r;
      canvas.width = W;
      canvas.height = H;
      view.fit(field, w, h);
      fieldLayer = F.renderLayer(field, view, W, H, dpr);
      layerDirty = false;
    }
  }

  function fieldToClient(x, y) {
    ensureSize();
    const b = canvas.getBoundingClientRect(), p = view.toScreen(x, y);
    return { x: b.left + p.x, y: b.top + p.y };
  }
  function clientToField(cx, cy) {
    ensureSize();
    const b = canvas.getBoundingClientRect();
    return view.toField(cx - b.left, cy - b.top);
  }

  const robotKey = (r) => `${r.team}:${r.id}`;
  const ballRadius = () => (api.state && api.state.ball && api.state.ball.r > 0 ? api.state.ball.r : 0.0215);
  const clampToCarpet = (v, half, r) => Math.max(-half + r, Math.min(half - r, v));
  const round4 = (v) => Math.round(v * 1e4) / 1e4;

  // ---------------------------------------------------------------- trails

  const trails = new Map();  // key -> [{t, x, y}] in sim time order
  let lastTrailT = -Infinity;
  const trailHold = new Map();  // key -> time (ms) until which our own move is still landing
  // Faster than anything on the field (8 m/s): a teleport, not motion.
  const jumped = (a, x, y, dt) => Math.hypot(x - a.x, y - a.y) > 0.05 + 8 * Math.max(0, dt);

  function recordTrails(s) {
    const t = s.t;
    if (!Number.isFinite(t)) return;
    if (t < lastTrailT) trails.clear();  // reset or time went back
    lastTrailT = t;
    const add = (key, x, y) => {
      if (!Number.isFinite(x) || !Number.isFinite(y)) return;
      if (trailHold.get(key) > performance.now()) {  // restart the trail where the drop lands
        trails.delete(key);
        return;
      }
      let tr = trails.get(key);
      if (!tr) trails.set(key, (tr = []));
      const last = tr[tr.length - 1];
      if (last) {
        if (t - last.t < TRAIL_MIN_DT) return;
        if (jumped(last, x, y, t - last.t)) tr.length = 0;  // a move or reset breaks the line
      }
      tr.push({ t, x, y });
      while (tr[0].t < t - TRAIL_SECONDS) tr.shift();
    };
    if (s.ball) add('ball', s.ball.x, s.ball.y);
    for (const r of Array.isArray(s.robots) ? s.robots : []) if (r && r.present !== false) add(robotKey(r), r.x, r.y);
    for (const [key, tr] of trails) if (!tr.length || tr[tr.length - 1].t < t - TRAIL_SECONDS) trails.delete(key);
  }

  function drawTrail(pts, head, t, color, width) {
    const all = head && pts.length && !jumped(pts[pts.length - 1], head.x, head.y, t - pts[pts.length - 1].t)
      ? pts.concat([{ t, x: head.x, y: head.y }]) : pts;
    ctx.strokeStyle = color;
    ctx.lineWidth = width;
    ctx.lineJoin = ctx.lineCap = 'round';
    for (let i = 0; i < all.length - 1; i += TRAIL_RUN) {
      const j = Math.min(i + TRAIL_RUN, all.length - 1);
      const age = t - all[(i + j) >> 1].t;
      ctx.globalAlpha = 0.65 * Math.max(0, 1 - age / TRAIL_SECONDS);
      ctx.beginPath();
      for (let k = i; k <= j; k++) {
        const p = view.toScreen(all[k].x, all[k].y);
        if (k === i) ctx.moveTo(p.x, p.y); else ctx.lineTo(p.x, p.y);
      }
      ctx.stroke();
    }
    ctx.globalAlpha = 1;
  }

  // ---------------------------------------------------------------- rendering

  let rafPending = false;
  function requestRender() {
    if (rafPending) return;
    rafPending = true;
    requestAnimationFrame(render);
  }
  new ResizeObserver(requestRender).observe(canvas);
  window.addEventListener('resize', requestRender);  // also catches devicePixelRatio changes (zoom)

  // Where to draw an object: the drag position while dragging, the drop point while the server
  // has not caught up yet, else the reported truth.
  function placed(kind, key, x, y, yaw) {
    if (drag && drag.kind === kind && drag.key === key) return { x: drag.x, y: drag.y, yaw: drag.yaw, held: true };
    if (settle && settle.kind === kind && settle.key === key) {
      if (performance.now() < settle.until && Math.hypot(x - settle.x, y - settle.y) > 0.02) {
        return { x: settle.x, y: settle.y, yaw: settle.yaw, held: true };
      }
      settle = null;
    }
    return { x, y, yaw, held: false };
  }

  function render() {
    rafPending = false;
    ensureSize();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(fieldLayer, 0, 0);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const b = canvas.getBoundingClientRect();
    const s = api.state;
    const drawn = { t: s && Number.isFinite(s.t) ? s.t : null, ball: null, robots: [], target: null };
    const showCams = $('cameras').checked;

    if (s) {
      const t = s.t;
      const robots = (Array.isArray(s.robots) ? s.robots : [])
        .filter((r) => r && r.present !== false && Number.isFinite(r.x) && Number.isFinite(r.y));
      const places = robots.map((r) => placed('robot', robotKey(r), r.x, r.y, Number.isFinite(r.yaw) ? r.yaw : 0));
      let ball = null;
      if (s.ball && Number.isFinite(s.ball.x) && Number.isFinite(s.ball.y)) {
        const br = ballRadius(), q = placed('ball', 'ball', s.ball.x, s.ball.y, 0);
        ball = { x: q.x, y: q.y, z: q.held ? br : (Number.isFinite(s.ball.z) ? s.ball.z : br), r: br };
      }

      if ($('trails').checked && Number.isFinite(t)) {
        robots.forEach((r, i) => {
          const tr = trails.get(robotKey(r));
          if (tr) drawTrail(tr, places[i], t, TEAM_FILL[r.team] || '#ccc', 3);
        });
        const tb = trails.get('ball');
        if (tb && ball) drawTrail(tb, ball, t, BALL_FILL, 2);
      }

      // Contact lines under the robots: only the stretch from the robot's edge to the ball shows.
      if (ball) {
        robots.forEach((r, i) => {
          if (!r.contact) return;
          const a = view.toScreen(places[i].x, places[i].y), c = view.toScreen(ball.x, ball.y);
          ctx.strokeStyle = CONTACT;
          ctx.lineWidth = 2;
          ctx.beginPath();
          ctx.moveTo(a.x, a.y);
          ctx.lineTo(c.x, c.y);
          ctx.stroke();
        });
      }
      // Under the robots and the ball: they may stand on it.
      const target = M.drawTarget(ctx, view, api.referee, TEAM_FILL, label);
      if (target) drawn.target = Object.assign(target, { cx: b.left + target.sx, cy: b.top + target.sy });
      const ballShown = ball ? drawBallShadow(ball) : null;
      robots.forEach((r, i) => {
        const p = places[i];
        const c = drawRobot(r, p.x, p.y, p.yaw);
        drawn.robots.push({ team: r.team, id: r.id, x: p.x, y: p.y, yaw: p.yaw, cx: b.left + c.x, cy: b.top + c.y });
      });
      if (ball) {
        const c = drawBall(ball, ballShown);
        drawn.ball = { x: ball.x, y: ball.y, z: ball.z, cx: b.left + c.x, cy: b.top + c.y,
          sx: b.left + ballShown.x, sy: b.top + ballShown.y };
      }
      if (showCams) drawDetections(s, robots);
    }
    if (showCams) drawCameras(s);
    if (drag && drag.kind === 'kick') drawKickArrow();
    if (!api.connected) drawBanner(everConnected ? 'disconnected' : 'connecting…');

    api.drawn = drawn;
    api.frames++;
  }

  // Returns the shadow's screen point (the ball's footprint on the carpet).
  function drawBallShadow(ball) {
    const p = view.toScreen(ball.x, ball.y), R = Math.max(3, ball.r * view.s);
    ctx.fillStyle = 'rgba(0,0,0,0.35)';
    ctx.beginPath();
    ctx.ellipse(p.x + 1, p.y + 1, R, R * 0.85, 0, 0, 2 * Math.PI);
    ctx.fill();
    return p;
  }

  // A ball in the air is drawn lifted on screen by its height (same scale) and a little larger.
  function drawBall(ball, ground) {
    const h = ball.z - ball.r;
    const air = h > 0.005;
    const lift = air ? h * view.s : 0;
    const R = Math.max(3, ball.r * view.s) * (air ? 1 + 0.3 * Math.min(h, 2) : 1);
    const c = { x: ground.x, y: ground.y - lift };
    if (air) {
      ctx.strokeStyle = 'rgba(255,255,255,0.5)';
      ctx.lineWidth = 1;
      ctx.setLineDash([2, 3]);
      ctx.beginPath();
      ctx.moveTo(ground.x, ground.y);
      ctx.lineTo(c.x, c.y);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    ctx.fillStyle = BALL_FILL;
    ctx.strokeStyle = '#4a2200';
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.arc(c.x, c.y, R, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    if (air) label(`${h.toFixed(2)} m`, c.x + R + 4, c.y, 'left');
    return c;
  }

  // Robot: disc with a flat front (the dribbler side) facing yaw; the id stays upright.
  const FRONT_CUT = 0.7;  // rad: half-angle of the flat front
  function drawRobot(r, x, y, yaw) {
    const p = view.toScreen(x, y);
    const R = Math.max(5, (r.r > 0 ? r.r : 0.09) * view.s);
    const a = -yaw;  // screen angles turn the other way (y flipped)
    const team = TEAM_FILL[r.team] ? r.team : null;
    if (selected === robotKey(r)) {  // the robot the panel shows
      ctx.strokeStyle = '#ffffff';
      ctx.lineWidth = 1.5;
      ctx.setLineDash([4, 3]);
      ctx.beginPath();
      ctx.arc(p.x, p.y, R + 7, 0, 2 * Math.PI);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    if (r.contact) {
      ctx.strokeStyle = CONTACT;
      ctx.lineWidth = 2.5;
      ctx.beginPath();
      ctx.arc(p.x, p.y, R + 3.5, 0, 2 * Math.PI);
      ctx.stroke();
    }
    ctx.beginPath();
    ctx.arc(p.x, p.y, R, a + FRONT_CUT, a - FRONT_CUT + 2 * Math.PI);
    ctx.closePath();
    ctx.fillStyle = team ? TEAM_FILL[team] : '#bbbbbb';
    ctx.fill();
    ctx.strokeStyle = '#101010';
    ctx.lineWidth = 1.5;
    ctx.stroke();
    // A dark bar on the flat front makes the heading readable at a glance.
    const f1 = { x: p.x + R * Math.cos(a - FRONT_CUT), y: p.y + R * Math.sin(a - FRONT_CUT) };
    const f2 = { x: p.x + R * Math.cos(a + FRONT_CUT), y: p.y + R * Math.sin(a + FRONT_CUT) };
    ctx.lineWidth = Math.max(2, R * 0.22);
    ctx.lineCap = 'butt';
    ctx.beginPath();
    ctx.moveTo(f1.x, f1.y);
    ctx.lineTo(f2.x, f2.y);
    ctx.stroke();
    if (r.kicker_ready) {
      const d = R * 0.6;
      ctx.fillStyle = '#39e35f';
      ctx.lineWidth = 0.75;
      ctx.beginPath();
      ctx.arc(p.x + d * Math.cos(a), p.y + d * Math.sin(a), Math.max(1.5, R * 0.11), 0, 2 * Math.PI);
      ctx.fill();
      ctx.stroke();
    }
    ctx.fillStyle = team ? TEAM_TEXT[team] : '#111';
    ctx.font = `bold ${Math.round(Math.max(9, R * 1.1))}px system-ui, sans-serif`;
    ctx.textAlign = 'center';
    ctx.textBaseline = 'middle';
    ctx.fillText(String(r.id), p.x, p.y + 0.5);
    return p;
  }

  // Camera detections as hollow outlines: the gap to the truth shows noise and latency.
  function drawDetections(s, robots) {
    const radius = new Map(robots.map((r) => [robotKey(r), r.r > 0 ? r.r : 0.09]));
    ctx.lineWidth = 1.5;
    for (const f of Array.isArray(s.vision) ? s.vision : []) {
      if (!f) continue;
      for (const d of Array.isArray(f.robots) ? f.robots : []) {
        if (!d || !Number.isFinite(d.x) || !Number.isFinite(d.y)) continue;
        const p = view.toScreen(d.x, d.y), R = Math.max(5, (radius.get(robotKey(d)) || 0.09) * view.s);
        ctx.strokeStyle = TEAM_LINE[d.team] || '#eee';
        ctx.beginPath();
        ctx.arc(p.x, p.y, R, 0, 2 * Math.PI);
        if (Number.isFinite(d.yaw)) {  // a tick outside the outline, clear of the id
          ctx.moveTo(p.x + R * Math.cos(-d.yaw), p.y + R * Math.sin(-d.yaw));
          ctx.lineTo(p.x + (R + 5) * Math.cos(-d.yaw), p.y + (R + 5) * Math.sin(-d.yaw));
        }
        ctx.stroke();
      }
      for (const d of Array.isArray(f.balls) ? f.balls : []) {
        if (!d || !Number.isFinite(d.x) || !Number.isFinite(d.y)) continue;
        const p = view.toScreen(d.x, d.y), R = Math.max(4, ballRadius() * view.s);
        ctx.strokeStyle = '#ffe2b0';
        ctx.beginPath();
        ctx.arc(p.x, p.y, R, 0, 2 * Math.PI);
        ctx.moveTo(p.x - R - 3, p.y);
        ctx.lineTo(p.x + R + 3, p.y);
        ctx.moveTo(p.x, p.y - R - 3);
        ctx.lineTo(p.x, p.y + R + 3);
        ctx.stroke();
      }
    }
  }

  // Camera positions, with each camera's latest frame age (sim time since capture).
  function drawCameras(s) {
    const frames = new Map();
    for (const f of s && Array.isArray(s.vision) ? s.vision : []) if (f) frames.set(f.camera, f);
    for (const c of cameras) {
      if (!c || !Number.isFinite(c.x) || !Number.isFinite(c.y)) continue;
      const p = view.toScreen(c.x, c.y);
      ctx.fillStyle = '#111';
      ctx.strokeStyle = '#fff';
      ctx.lineWidth = 1;
      ctx.fillRect(p.x - 5, p.y - 5, 10, 10);
      ctx.strokeRect(p.x - 5, p.y - 5, 10, 10);
      ctx.beginPath();
      ctx.arc(p.x, p.y, 2.5, 0, 2 * Math.PI);
      ctx.stroke();
      const f = frames.get(c.id);
      const age = f && s && Number.isFinite(f.t_capture) && Number.isFinite(s.t)
        ? ` · ${Math.round((s.t - f.t_capture) * 1000)} ms` : '';
      label(`cam ${c.id}${age}`, p.x + 8, p.y - 9, 'left');
    }
  }

  function drawKickArrow() {
    const k = kickVector();
    if (!k) return;
    const b = view.toScreen(k.bx, k.by), e = view.toScreen(drag.x, drag.y);
    const ang = Math.atan2(e.y - b.y, e.x - b.x), head = 10;
    const gap = Math.max(3, ballRadius() * view.s) + 2;  // start at the ball's edge, leave it visible
    const a = { x: b.x + gap * Math.cos(ang), y: b.y + gap * Math.sin(ang) };
    ctx.lineCap = 'round';
    for (const [color, width] of [['rgba(0,0,0,0.6)', 5], ['#ffffff', 2.5]]) {
      ctx.strokeStyle = color;
      ctx.lineWidth = width;
      ctx.beginPath();
      ctx.moveTo(a.x, a.y);
      ctx.lineTo(e.x, e.y);
      ctx.moveTo(e.x - head * Math.cos(ang - 0.45), e.y - head * Math.sin(ang - 0.45));
      ctx.lineTo(e.x, e.y);
      ctx.lineTo(e.x - head * Math.cos(ang + 0.45), e.y - head * Math.sin(ang + 0.45));
      ctx.stroke();
    }
    const capped = k.len * KICK_GAIN > KICK_MAX ? ' (max)' : '';
    label(`${k.speed.toFixed(1)} m/s${capped}${$('chip').checked ? ' · chip 45°' : ''}`, e.x + 10, e.y - 12, 'left');
  }

  function drawBanner(text) {
    ctx.font = 'bold 15px system-ui, sans-serif';
    const w = ctx.measureText(text).width + 24, x = canvas.clientWidth / 2;
    ctx.fillStyle = 'rgba(120,20,20,0.85)';
    ctx.fillRect(x - w / 2, 10, w, 28);
    ctx.fillStyle = '#fff';
    ctx.textAlign = 'center';
    ctx.textBaseline = 'middle';
    ctx.fillText(text, x, 24);
  }

  // Small text with a dark halo so it reads on carpet, lines and robots alike.
  function label(text, x, y, align) {
    ctx.font = '12px system-ui, sans-serif';
    ctx.textAlign = align;
    ctx.textBaseline = 'middle';
    ctx.lineJoin = 'round';
    ctx.lineWidth = 3;
    ctx.strokeStyle = 'rgba(0,0,0,0.75)';
    ctx.strokeText(text, x, y);
    ctx.fillStyle = '#fff';
    ctx.fillText(text, x, y);
  }

  // ---------------------------------------------------------------- gestures

  let drag = null;    // {kind: 'ball'|'robot'|'kick', key, pointerId, x, y, yaw, ...}
  let settle = null;  // {kind, key, x, y, yaw, until}: drop point held until the state shows it

  // What is under a client point, judged against what the last frame drew. The ball wins
  // over robots: it is small and often touches one.
  function hitTest(cx, cy, pointerType) {
    const d = api.drawn;
    if (!d) return null;
    const minR = pointerType === 'touch' ? 2 * HIT_PX : HIT_PX;
    if (d.ball) {
      const R = Math.max(minR, ballRadius() * view.s);
      if (Math.hypot(cx - d.ball.cx, cy - d.ball.cy) <= R || Math.hypot(cx - d.ball.sx, cy - d.ball.sy) <= R) {
        return { kind: 'ball', key: 'ball' };
      }
    }
    let best = null, bestD = Infinity;
    const byKey = new Map((api.state && Array.isArray(api.state.robots) ? api.state.robots : [])
      .filter(Boolean).map((r) => [robotKey(r), r]));
    for (const r of d.robots) {
      const src = byKey.get(robotKey(r)) || {};
      const dist = Math.hypot(cx - r.cx, cy - r.cy);
      if (dist <= Math.max(minR, (src.r > 0 ? src.r : 0.09) * view.s) && dist < bestD) {
        best = { kind: 'robot', key: robotKey(r), team: r.team, id: r.id, x: r.x, y: r.y, yaw: r.yaw, r: src.r || 0.09 };
        bestD = dist;
      }
    }
    return best;
  }

  function currentBall() {
    const b = api.state && api.state.ball;
    return b && Number.isFinite(b.x) && Number.isFinite(b.y) ? b : null;
  }

  function kickVector() {
    const b = currentBall();
    if (!b || !drag) return null;
    const dx = drag.x - b.x, dy = drag.y - b.y, len = Math.hypot(dx, dy);
    if (len * view.s < 4) return null;  // too short to mean a kick
    return { bx: b.x, by: b.y, ux: dx / len, uy: dy / len, len, speed: Math.min(len * KICK_GAIN, KICK_MAX) };
  }

  function sendMove(d) {
    const r = d.kind === 'ball' ? ballRadius() : d.r;
    // Keep the drop point on the carpet so the server has no reason to refuse it.
    const x = round4(clampToCarpet(d.x, field.carpetL / 2, r)), y = round4(clampToCarpet(d.y, field.carpetW / 2, r));
    if (d.kind === 'ball') send({ cmd: 'move', target: 'ball', x, y });
    else send({ cmd: 'move', target: { team: d.team, id: d.id }, x, y, yaw: d.yaw });  // unrounded: stays within [-pi, pi]
    d.lastSent = performance.now();
    d.dirty = false;
    trailHold.set(d.key, d.lastSent + 300);
  }

  // Throttle: at most one move per MOVE_INTERVAL, the latest position always goes out.
  function queueMove() {
    const d = drag;
    d.dirty = true;
    if (d.timer) return;
    const wait = d.lastSent + MOVE_INTERVAL - performance.now();
    if (wait <= 0) sendMove(d);
    else d.timer = setTimeout(() => { d.timer = 0; if (d === drag && d.dirty) sendMove(d); }, wait);
  }

  function pointerField(e) { return clientToField(e.clientX, e.clientY); }

  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    if (drag || (e.button !== 0 && e.button !== 2)) return;
    const hit = hitTest(e.clientX, e.clientY, e.pointerType);
    if (!hit) {  // a click on the carpet closes the robot panel, and does nothing else
      if (e.button === 0 && selected) select(null);
      return;
    }
    if (R.active()) {  // a log cannot be changed: a click on a robot shows its panel, nothing drags
      if (e.button === 0 && hit.kind === 'robot') select(selected === hit.key ? null : hit.key);
      return;
    }
    const kick = hit.kind === 'ball' && (e.button === 2 || e.shiftKey || $('kick-mode').checked);
    if (!kick && e.button === 2) return;
    const p = pointerField(e);
    drag = Object.assign(hit, {
      kind: kick ? 'kick' : hit.kind, pointerId: e.pointerId, lastSent: -Infinity, timer: 0,
      dirty: false, moved: false, startX: e.clientX, startY: e.clientY,
      // Robots keep the grab offset; the ball sits at the pointer.
      offX: hit.kind === 'robot' ? hit.x - p.x : 0, offY: hit.kind === 'robot' ? hit.y - p.y : 0,
    });
    drag.x = p.x + drag.offX;
    drag.y = p.y + drag.offY;
    settle = null;
    canvas.setPointerCapture(e.pointerId);
    canvas.className = kick ? 'kick' : 'dragging';
    e.preventDefault();
    requestRender();
  });

  canvas.addEventListener('pointermove', (e) => {
    if (!drag) {
      if (e.pointerType === 'mouse') {
        const hit = R.active() ? null : hitTest(e.clientX, e.clientY, 'mouse');
        canvas.className = !hit ? '' : hit.kind === 'ball' && (e.shiftKey || $('kick-mode').checked) ? 'kick' : 'grab';
      }
      return;
    }
    if (e.pointerId !== drag.pointerId) return;
    const p = pointerField(e);
    drag.x = p.x + drag.offX;
    drag.y = p.y + drag.offY;
    if (!drag.moved && Math.hypot(e.clientX - drag.startX, e.clientY - drag.startY) < 3) return;
    drag.moved = true;
    if (drag.kind !== 'kick') queueMove();
    requestRender();
  });

  function endDrag(e, cancelled) {
    if (!drag || e.pointerId !== drag.pointerId) return;
    const d = drag;
    clearTimeout(d.timer);
    if (d.kind === 'kick') {
      const k = cancelled ? null : kickVector();
      if (k) {
        const chip = $('chip').checked;
        const h = chip ? k.speed * Math.SQRT1_2 : k.speed, vz = chip ? k.speed * Math.SQRT1_2 : 0;
        const r3 = (v) => Math.round(v * 1000) / 1000;
        send({ cmd: 'kick', vx: r3(k.ux * h), vy: r3(k.uy * h), vz: r3(vz) });
      }
    } else if (d.moved || d.dirty) {
      sendMove(d);  // the final point, always
      settle = { kind: d.kind, key: d.key, x: d.x, y: d.y, yaw: d.yaw, until: performance.now() + SETTLE_MS };
      setTimeout(requestRender, SETTLE_MS + 20);
    } else if (d.kind === 'robot' && !cancelled) {
      select(selected === d.key ? null : d.key);  // a click, not a drag: show (or hide) its panel
    }
    drag = null;
    canvas.className = '';
    if (canvas.hasPointerCapture(e.pointerId)) canvas.releasePointerCapture(e.pointerId);
    requestRender();
  }
  canvas.addEventListener('pointerup', (e) => endDrag(e, false));
  // A cancelled move still lands where it was dragged; a cancelled kick is dropped.
  canvas.addEventListener('pointercancel', (e) => endDrag(e, true));
  canvas.addEventListener('lostpointercapture', (e) => endDrag(e, true));

  function rotateDrag(da) {
    drag.yaw = Math.atan2(Math.sin(drag.yaw + da), Math.cos(drag.yaw + da));
    drag.moved = true;
    queueMove();
    requestRender();
  }
  canvas.addEventListener('wheel', (e) => {
    if (!drag || drag.kind !== 'robot' || !e.deltaY) return;
    e.preventDefault();
    rotateDrag(e.deltaY < 0 ? ROTATE_STEP : -ROTATE_STEP);  // wheel up: counter-clockwise
  }, { passive: false });

  connect();
  requestRender();
})();
