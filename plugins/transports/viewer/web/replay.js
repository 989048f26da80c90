// SPDX-License-Identifier: Apache-2.0
// replay.js: a log played back (`ubersim replay FILE --viewer`, the hello's "replay"): the time
// slider, play/pause and speed under the field, in place of the controls that change a world.
// The server keeps the clock; the page sends seek, play, pause and speed and shows where the
// states say the replay is. viewer.js feeds it the hello and the states and asks active().
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const SEEK_INTERVAL = 50;  // ms: seeks while dragging go out at ~20 Hz
  const HOLD_MS = 1000;      // after a seek, the slider stays there until a state shows it (at most this long)
  const SKIP = 5;            // s: the arrow keys

  let active = false;
  let duration = 0;
  let replay = null;         // the last state's status.replay
  let dragging = false;
  let held = null;           // {t, until}: a seek sent, not yet seen in a state
  let lastSeek = -Infinity;
  let seekTimer = 0;
  let lastSpeed = null;

  const send = (msg) => (window.ubersimViewer ? window.ubersimViewer.send(msg) : null);

  // s as m:ss.s, or h:mm:ss.s from an hour on.
  function clock(t) {
    if (!Number.isFinite(t)) return '–';
    const s = Math.max(0, t);
    const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = (s % 60).toFixed(1).padStart(4, '0');
    return h > 0 ? `${h}:${String(m).padStart(2, '0')}:${sec}` : `${m}:${sec}`;
  }

  function setText(id, text) {
    const el = $(id);
    if (el.textContent !== text) el.textContent = text;
  }

  // The hello: a replay shows its bar and hides the world's controls; a live world the other way.
  function hello(m) {
    const r = m && m.replay && typeof m.replay === 'object' ? m.replay : null;
    active = !!r;
    document.body.classList.toggle('replay', active);
    $('replay-bar').hidden = !active;
    if (!active) return;
    duration = Number.isFinite(r.duration) ? Math.max(0, r.duration) : 0;
    const slider = $('replay-slider');
    slider.max = String(duration);
    setText('replay-total', clock(duration));
    const start = Number.isFinite(r.start_unix) && r.start_unix > 0
      ? ` · recorded ${new Date(r.start_unix * 1000).toISOString().replace('T', ' ').slice(0, 19)} UTC` : '';
    setText('replay-file', `${typeof r.file === 'string' ? r.file : ''}${start}${r.sending ? ' · also sent on the network' : ''}`);
  }

  function shownTime() {
    if (dragging) return Number($('replay-slider').value);
    if (held && performance.now() < held.until && replay && Math.abs(replay.t - held.t) > 0.25) return held.t;
    held = null;
    return replay ? replay.t : 0;
  }

  // A state: where the replay stands.
  function state(s) {
    if (!active) return;
    const r = s && s.status && s.status.replay;
    if (!r || typeof r !== 'object') return;
    replay = r;
    const t = shownTime();
    const slider = $('replay-slider');
    if (!dragging && Number(slider.value) !== t) slider.value = String(t);
    setText('replay-time', clock(t));
    setText('replay-play', r.playing ? 'Pause' : (r.t >= duration - 1e-6 ? 'Replay' : 'Play'));
    const sel = $('replay-speed');
    if (r.speed !== lastSpeed && document.activeElement !== sel) {
      lastSpeed = r.speed;
      const v = String(r.speed);
      if ([...sel.options].some((o) => o.value === v)) sel.value = v;
    }
  }

  function seek(t) {
    const v = Math.max(0, Math.min(duration, t));
    held = { t: v, until: performance.now() + HOLD_MS };
    lastSeek = performance.now();
    send({ cmd: 'seek', t: Math.round(v * 1000) / 1000 });
    setText('replay-time', clock(v));
  }

  // Throttled while dragging: at most one seek per SEEK_INTERVAL, the latest value always goes out.
  function seekSoon() {
    if (seekTimer) return;
    const wait = lastSeek + SEEK_INTERVAL - performance.now();
    if (wait <= 0) {
      seek(Number($('replay-slider').value));
      return;
    }
    seekTimer = setTimeout(() => {
      seekTimer = 0;
      seek(Number($('replay-slider').value));
    }, wait);
  }

  function togglePlay() {
    if (!replay) return;
    send({ cmd: replay.playing ? 'pause' : 'play' });
  }

  function skip(dt) {
    seek(shownTime() + dt);
  }

  const slider = $('replay-slider');
  slider.addEventListener('input', () => {
    dragging = true;
    setText('replay-time', clock(Number(slider.value)));
    seekSoon();
  });
  slider.addEventListener('change', () => {
    clearTimeout(seekTimer);
    seekTimer = 0;
    seek(Number(slider.value));
    dragging = false;
    slider.blur();  // space and the arrows go back to the replay
  });
  $('replay-play').addEventListener('click', (e) => { togglePlay(); e.currentTarget.blur(); });
  $('replay-speed').addEventListener('change', (e) => {
    send({ cmd: 'speed', factor: Number(e.target.value) });
    e.target.blur();
  });

  window.UberSimReplay = { hello, state, togglePlay, skip, active: () => active, clock };
})();
