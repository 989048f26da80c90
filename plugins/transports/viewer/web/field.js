// SPDX-License-Identifier: Apache-2.0
// field.js: the field geometry from the server's hello, the field <-> screen transform, and the
// static field layer (carpet, walls, lines, arcs, goals). The layer only changes on resize or a
// new hello, so it is drawn once into an offscreen canvas and blitted every frame.
'use strict';
(function () {
  const WALL = 0.05;       // m: drawn wall thickness outside the carpet
  const GOAL_WALL = 0.02;  // m: drawn goal wall thickness
  const MARGIN = 12;       // CSS px kept free around the drawing

  const num = (v, d) => (Number.isFinite(v) ? v : d);
  const finite = (...v) => v.every(Number.isFinite);

  // Fill in defaults (Division B) so drawing never meets a missing number.
  function normalize(f) {
    f = f && typeof f === 'object' ? f : {};
    const L = num(f.field_length, 9), W = num(f.field_width, 6), b = num(f.boundary_width, 0.3);
    return {
      name: String(f.name || ''), L, W,
      goalWidth: num(f.goal_width, 1), goalDepth: num(f.goal_depth, 0.18),
      carpetL: num(f.carpet_length, L + 2 * b), carpetW: num(f.carpet_width, W + 2 * b),
      penDepth: num(f.penalty_area_depth, 1), penWidth: num(f.penalty_area_width, 2),
      circle: num(f.center_circle_radius, 0.5), thick: num(f.line_thickness, 0.01),
      lines: (Array.isArray(f.lines) ? f.lines : []).filter((l) => l && finite(l.x1, l.y1, l.x2, l.y2)),
      arcs: (Array.isArray(f.arcs) ? f.arcs : []).filter((a) => a && finite(a.cx, a.cy, a.radius, a.a1, a.a2)),
    };
  }

  // Uniform scale, field centre at the canvas centre, y flipped (field y up, screen y down).
  class View {
    constructor() { this.s = 100; this.ox = 0; this.oy = 0; }
    fit(f, w, h) {
      const hx = Math.max(f.carpetL / 2 + WALL, f.L / 2 + f.goalDepth + GOAL_WALL);
      const hy = Math.max(f.carpetW / 2 + WALL, f.goalWidth / 2 + GOAL_WALL);
      this.s = Math.max(1e-3, Math.min((w - 2 * MARGIN) / (2 * hx), (h - 2 * MARGIN) / (2 * hy)));
      this.ox = w / 2;
      this.oy = h / 2;
    }
    toScreen(x, y) { return { x: this.ox + x * this.s, y: this.oy - y * this.s }; }
    toField(X, Y) { return { x: (X - this.ox) / this.s, y: (this.oy - Y) / this.s }; }
  }

  // Field lines as listed by the server, or a minimal set when it sent none.
  function fallbackLines(f) {
    const l = f.L / 2, w = f.W / 2, pd = f.penDepth, pw = f.penWidth / 2, t = f.thick;
    const seg = (x1, y1, x2, y2) => ({ x1, y1, x2, y2, thickness: t });
    const out = [seg(-l, w, l, w), seg(-l, -w, l, -w), seg(-l, -w, -l, w), seg(l, -w, l, w),
      seg(0, -w, 0, w), seg(-l, 0, l, 0)];
    for (const sx of [-1, 1]) {
      out.push(seg(sx * l, pw, sx * (l - pd), pw), seg(sx * l, -pw, sx * (l - pd), -pw),
        seg(sx * (l - pd), -pw, sx * (l - pd), pw));
    }
    return out;
  }

  // Draws the static layer into a new canvas of W x H device pixels.
  function renderLayer(f, view, W, H, dpr) {
    const layer = document.createElement('canvas');
    layer.width = W;
    layer.height = H;
    const g = layer.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const s = view.s;
    const P = (x, y) => view.toScreen(x, y);
    const rect = (x1, y1, x2, y2, style) => {
      const a = P(Math.min(x1, x2), Math.max(y1, y2));
      g.fillStyle = style;
      g.fillRect(a.x, a.y, Math.abs(x2 - x1) * s, Math.abs(y2 - y1) * s);
    };
    const cl = f.carpetL / 2, cw = f.carpetW / 2;
    rect(-cl - WALL, -cw - WALL, cl + WALL, cw + WALL, '#1c1d20');  // walls
    rect(-cl, -cw, cl, cw, '#2e8b3e');                              // carpet

    // Lines are centre lines; a thin line still gets one CSS pixel so it stays visible.
    g.strokeStyle = '#f4f4f4';
    g.lineCap = 'square';
    const lines = f.lines.length ? f.lines : fallbackLines(f);
    for (const l of lines) {
      const a = P(l.x1, l.y1), b = P(l.x2, l.y2);
      g.lineWidth = Math.max(1, num(l.thickness, f.thick) * s);
      g.beginPath();
      g.moveTo(a.x, a.y);
      g.lineTo(b.x, b.y);
      g.stroke();
    }
    const arcs = f.arcs.length || f.lines.length ? f.arcs
      : [{ cx: 0, cy: 0, radius: f.circle, a1: 0, a2: 2 * Math.PI }];
    g.lineCap = 'butt';
    for (const a of arcs) {
      const c = P(a.cx, a.cy);
      g.lineWidth = Math.max(1, num(a.thickness, f.thick) * s);
      g.beginPath();
      // y is flipped, so the field's counter-clockwise sweep a1 -> a2 is -a1 -> -a2 anticlockwise.
      g.arc(c.x, c.y, Math.max(0, a.radius * s), -a.a1, -a.a2, true);
      g.stroke();
    }

    // Goals: inner opening goalWidth, goalDepth deep behind each goal line; walls outside that.
    // At least 3 CSS px thick so the goal still reads on a small window.
    const gw = f.goalWidth / 2, t = Math.max(GOAL_WALL, 3 / s);
    for (const sx of [-1, 1]) {
      const x0 = sx * f.L / 2, x1 = sx * (f.L / 2 + f.goalDepth), x2 = sx * (f.L / 2 + f.goalDepth + t);
      g.beginPath();
      for (const [x, y] of [[x0, gw + t], [x2, gw + t], [x2, -gw - t], [x0, -gw - t],
        [x0, -gw], [x1, -gw], [x1, gw], [x0, gw]]) {
        const p = P(x, y);
        g.lineTo(p.x, p.y);
      }
      g.closePath();
      g.fillStyle = '#34363b';
      g.fill();
      g.lineWidth = 0.75;
      g.lineJoin = 'miter';
      g.strokeStyle = '#e6e6e6';
      g.stroke();
    }
    return layer;
  }

  window.UberSimField = { normalize, View, renderLayer, WALL };
})();
