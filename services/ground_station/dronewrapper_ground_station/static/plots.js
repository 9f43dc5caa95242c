// Small hand-written canvas plots: time series over the last minute, autoscaled.
"use strict";

// the labels' font: the page's small text (.muted, 12 CSS px), whatever the plot's width
const PLOT_FONT = "12px system-ui, -apple-system, \"Segoe UI\", Roboto, \"DejaVu Sans\", sans-serif";

class TimePlot {
  // canvas: a <canvas>; series: [{name, color}]; windowS: seconds shown.
  constructor(canvas, series, windowS = 60) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.series = series.map((s) => ({ ...s, points: [] }));
    this.windowS = windowS;
  }

  // Append value v (or skip when not a finite number) of series i at time t (s).
  push(i, t, v) {
    if (typeof v !== "number" || !Number.isFinite(v)) return;
    const pts = this.series[i].points;
    pts.push([t, v]);
    while (pts.length && pts[0][0] < t - this.windowS) pts.shift();
  }

  clear() { for (const s of this.series) s.points = []; }

  // Match the canvas's pixels to its size on screen (CSS px times the device pixel ratio), so
  // lines and labels are drawn at their size, sharp, never stretched; w, h: CSS px.
  fit() {
    const { canvas, ctx } = this, dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, canvas.clientWidth), h = Math.max(1, canvas.clientHeight);
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    }
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return [w, h];
  }

  draw(now) {
    const { ctx } = this;
    const [w, h] = this.fit(), padL = 44, padB = 18, padT = 18;
    ctx.clearRect(0, 0, w, h);
    let lo = Infinity, hi = -Infinity;
    for (const s of this.series) for (const [, v] of s.points) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (!Number.isFinite(lo)) { lo = -1; hi = 1; }
    if (hi - lo < 0.5) { const m = (hi + lo) / 2; lo = m - 0.25; hi = m + 0.25; }
    const margin = (hi - lo) * 0.1; lo -= margin; hi += margin;
    const x = (t) => padL + ((t - (now - this.windowS)) / this.windowS) * (w - padL - 4);
    const y = (v) => padT + (1 - (v - lo) / (hi - lo)) * (h - padT - padB);
    ctx.font = PLOT_FONT;
    ctx.strokeStyle = "#2b3540"; ctx.fillStyle = "#8b98a5"; ctx.lineWidth = 1;
    for (let k = 0; k <= 4; k++) {
      const v = lo + ((hi - lo) * k) / 4, yy = Math.round(y(v)) + 0.5;
      ctx.beginPath(); ctx.moveTo(padL, yy); ctx.lineTo(w, yy); ctx.stroke();
      ctx.fillText(v.toFixed(Math.abs(hi - lo) < 5 ? 2 : 1), 2, yy + 4);
    }
    if (lo < 0 && hi > 0) {
      ctx.strokeStyle = "#4a5866"; ctx.beginPath(); ctx.moveTo(padL, y(0)); ctx.lineTo(w, y(0)); ctx.stroke();
    }
    ctx.fillText("-60 s", padL, h - 4); ctx.textAlign = "right"; ctx.fillText("now", w - 2, h - 4);
    ctx.textAlign = "left";
    let legendX = padL;
    for (const s of this.series) {
      ctx.strokeStyle = s.color; ctx.lineWidth = 1.6; ctx.beginPath();
      s.points.forEach(([t, v], k) => (k ? ctx.lineTo(x(t), y(v)) : ctx.moveTo(x(t), y(v))));
      ctx.stroke();
      ctx.fillStyle = s.color; ctx.fillText(s.name, legendX, 13);
      legendX += ctx.measureText(s.name).width + 12;
    }
  }
}

window.TimePlot = TimePlot;
