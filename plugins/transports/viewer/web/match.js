// SPDX-License-Identifier: Apache-2.0
// match.js: the match as the referee publishes it (the server's "referee" messages, SI units):
// the scoreboard bar above the field and the placement target drawn on it. viewer.js feeds it
// the messages and calls drawTarget while it draws a frame. Text from the referee (team names,
// the status message) is untrusted: it only ever goes into textContent.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const SILENT_AFTER = 3;            // s without a Referee message (world running) before the hint says so
  const PLACEMENT_TOLERANCE = 0.15;  // m: the rules' placement precision, the target circle's radius

  const STAGES = {
    NORMAL_FIRST_HALF_PRE: '1st half (pre)', NORMAL_FIRST_HALF: '1st half', NORMAL_HALF_TIME: 'half time',
    NORMAL_SECOND_HALF_PRE: '2nd half (pre)', NORMAL_SECOND_HALF: '2nd half', EXTRA_TIME_BREAK: 'extra time break',
    EXTRA_FIRST_HALF_PRE: 'extra 1st half (pre)', EXTRA_FIRST_HALF: 'extra 1st half', EXTRA_HALF_TIME: 'extra half time',
    EXTRA_SECOND_HALF_PRE: 'extra 2nd half (pre)', EXTRA_SECOND_HALF: 'extra 2nd half',
    PENALTY_SHOOTOUT_BREAK: 'shoot-out break', PENALTY_SHOOTOUT: 'penalty shoot-out', POST_GAME: 'game over',
  };
  // Commands without their team suffix.
  const COMMANDS = {
    HALT: 'Halt', STOP: 'Stop', NORMAL_START: 'Normal start', FORCE_START: 'Force start',
    PREPARE_KICKOFF: 'Kick-off', PREPARE_PENALTY: 'Penalty', DIRECT_FREE: 'Free kick',
    INDIRECT_FREE: 'Indirect free kick', TIMEOUT: 'Timeout', GOAL: 'Goal', BALL_PLACEMENT: 'Ball placement',
  };

  // "SOME_NAME" → "Some name".
  function humanize(name) {
    const t = String(name).toLowerCase().replace(/_/g, ' ');
    return t.charAt(0).toUpperCase() + t.slice(1);
  }

  // "BALL_PLACEMENT_BLUE" → {base: 'BALL_PLACEMENT', team: 'blue', text: 'Ball placement blue'}.
  function command(name) {
    if (typeof name !== 'string') return null;
    const m = /^(.*)_(YELLOW|BLUE)$/.exec(name);
    const base = m ? m[1] : name, team = m ? m[2].toLowerCase() : null;
    const text = COMMANDS[base] || humanize(base);
    return { base, team, text: team ? `${text} ${team}` : text };
  }

  // Seconds as mm:ss; negative (a half run over) with a minus sign.
  function clock(s) {
    if (!Number.isFinite(s)) return '–';
    const a = Math.floor(Math.abs(s));
    return `${s < 0 ? '-' : ''}${String(Math.floor(a / 60)).padStart(2, '0')}:${String(a % 60).padStart(2, '0')}`;
  }

  function setText(el, text) {
    if (el.textContent !== text) el.textContent = text;
  }
  function setClass(el, name) {
    if (el.className !== name) el.className = name;
  }
  function span(cls, text) {
    const e = document.createElement('span');
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  // One team's block: name in its colour, cards with their time left, keeper and fouls.
  function teamBlock(el, color, t) {
    const cardTimes = Array.isArray(t.yellow_card_times) ? t.yellow_card_times.filter(Number.isFinite) : [];
    const sig = JSON.stringify([color, t.name, t.yellow_cards, cardTimes.map((s) => clock(s)), t.red_cards,
      t.goalkeeper, t.fouls]);
    if (el.dataset.sig === sig) return;
    el.dataset.sig = sig;
    el.replaceChildren();
    el.append(span(`sb-name ${color}`, typeof t.name === 'string' && t.name ? t.name : color));
    const cards = span('sb-cards');
    if (t.yellow_cards > 0) {
      const times = cardTimes.length ? ` (${cardTimes.map(clock).join(', ')})` : '';
      cards.append(span('card yc'), `${t.yellow_cards}${times}`);
      cards.title = 'yellow cards (time left)';
    }
    if (t.red_cards > 0) cards.append(' ', span('card rc'), String(t.red_cards));
    if (cards.childNodes.length) el.append(cards);
    const detail = [];
    if (Number.isFinite(t.goalkeeper)) detail.push(`keeper ${t.goalkeeper}`);
    if (Number.isFinite(t.fouls)) detail.push(`fouls ${t.fouls}`);
    if (detail.length) el.append(span('sb-detail', detail.join(' · ')));
  }

  // The team on the negative half is drawn on the left (the field's -x is on the left).
  function sides(ref) {
    return ref.blue_team_on_positive_half === false ? ['blue', 'yellow'] : ['yellow', 'blue'];
  }

  function eventText(e) {
    if (!e || typeof e.type !== 'string') return '';
    let by = '';
    if (e.by_team) by = Number.isFinite(e.by_bot) ? ` · ${e.by_team} ${e.by_bot}` : ` · ${e.by_team}`;
    return `${humanize(e.type)}${by}`;
  }

  // Updates the bar. `hello` says whether the viewer listens (hello.referee, "group:port"),
  // `ref` is the last referee message (or null), `status` the last state's status.
  function update(hello, ref, status) {
    const board = $('scoreboard');
    const source = hello && typeof hello.referee === 'string' ? hello.referee : null;
    if (board.hidden !== !source) board.hidden = !source;
    if (!source) return;
    const age = status && Number.isFinite(status.referee_age) ? status.referee_age : null;
    let hint = '';
    const replay = !!(hello && hello.replay);  // a log: its times, not the wall clock's
    if (!ref) hint = replay ? 'no referee message yet at this time of the log' : `no referee · listening on ${source}`;
    else if (age !== null && age > SILENT_AFTER && (replay || !(status && status.paused))) {
      hint = replay ? `no referee message for ${Math.round(age)} s in the log` : `referee silent for ${Math.round(age)} s`;
    }
    setText($('sb-hint'), hint);
    const match = $('sb-match');
    if (match.hidden !== !ref) match.hidden = !ref;
    if (!ref) return;

    const [left, right] = sides(ref);
    const team = (c) => (ref[c] && typeof ref[c] === 'object' ? ref[c] : {});
    teamBlock($('sb-left'), left, team(left));
    teamBlock($('sb-right'), right, team(right));
    const score = (c) => (Number.isFinite(team(c).score) ? team(c).score : '–');
    setText($('sb-score'), `${score(left)} : ${score(right)}`);
    setText($('sb-stage'), STAGES[ref.stage] || humanize(ref.stage || '–'));
    setText($('sb-clock'), ref.stage_time_left === null ? '' : clock(ref.stage_time_left));

    const c = command(ref.command), n = command(ref.next_command);
    setText($('sb-command'), c ? c.text : '–');
    setClass($('sb-command'), c && c.team ? `team-${c.team}` : '');
    setText($('sb-next'), n ? `next: ${n.text}` : '');
    // The time the current action (placement, free kick, kick-off) has left; none once it ran out.
    const action = ref.action_time_left;
    setText($('sb-action'), Number.isFinite(action) && action > 0 ? `action ${action.toFixed(1)} s` : '');
    const e = ref.game_event;
    setText($('sb-event'), e ? `last event: ${eventText(e)}` : '');
    setClass($('sb-event'), e && e.current === false ? 'old' : '');
    const said = typeof ref.status_message === 'string' ? ref.status_message : '';
    setText($('sb-status'), said);
    const sep = $('sb-event-sep');
    if (sep.hidden !== !(e || said)) sep.hidden = !(e || said);
  }

  // What the designated position is for, from the command and the one that follows.
  function targetName(ref) {
    const c = command(ref.command), n = command(ref.next_command);
    if (c && c.base === 'BALL_PLACEMENT') return { text: `ball placement ${c.team || ''}`.trim(), team: c.team };
    const why = { PREPARE_KICKOFF: 'kick-off', DIRECT_FREE: 'free kick', INDIRECT_FREE: 'free kick', PREPARE_PENALTY: 'penalty' };
    const next = n && why[n.base];
    return { text: next ? `${next} ${n.team || ''}`.trim() : 'designated position', team: next ? n.team : null };
  }

  // The designated position as a circle of the placement tolerance with a cross, in the placing
  // (or kicking) team's colour. Returns where it was drawn, or null.
  function drawTarget(ctx, view, ref, teamFill, label) {
    const p = ref && ref.designated_position;
    if (!p || !Number.isFinite(p.x) || !Number.isFinite(p.y)) return null;
    const what = targetName(ref);
    const color = teamFill[what.team] || '#ffffff';
    const s = view.toScreen(p.x, p.y), R = Math.max(6, PLACEMENT_TOLERANCE * view.s), arm = R + 6;
    ctx.setLineDash([]);
    ctx.lineCap = 'butt';
    for (const [stroke, width] of [['rgba(0,0,0,0.65)', 5], [color, 3]]) {  // a dark halo, then the colour
      ctx.strokeStyle = stroke;
      ctx.lineWidth = width;
      ctx.beginPath();
      ctx.arc(s.x, s.y, R, 0, 2 * Math.PI);
      ctx.moveTo(s.x - arm, s.y);
      ctx.lineTo(s.x + arm, s.y);
      ctx.moveTo(s.x, s.y - arm);
      ctx.lineTo(s.x, s.y + arm);
      ctx.stroke();
    }
    label(what.text, s.x, s.y - arm - 8, 'center');
    return { x: p.x, y: p.y, sx: s.x, sy: s.y, color, text: what.text };
  }

  window.UberSimMatch = { update, drawTarget, clock, command };
})();
