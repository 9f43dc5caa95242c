// Teleop inputs: on-screen sticks (pointer events), keyboard and a gamepad (Gamepad API).
// Each gives stick deflections in [-1, 1]; "active" means a person is holding it now.
"use strict";

class Stick {
  // A round touch pad: while pressed, x and y in [-1, 1] (right and down positive).
  constructor(canvas) {
    this.canvas = canvas; this.ctx = canvas.getContext("2d");
    this.x = 0; this.y = 0; this.active = false; this.enabled = true;
    const move = (e) => {
      const r = canvas.getBoundingClientRect();
      let x = ((e.clientX - r.left) / r.width) * 2 - 1, y = ((e.clientY - r.top) / r.height) * 2 - 1;
      const n = Math.hypot(x, y); if (n > 1) { x /= n; y /= n; }
      this.x = x; this.y = y; this.draw();
    };
    canvas.addEventListener("pointerdown", (e) => {
      if (!this.enabled) return;
      canvas.setPointerCapture(e.pointerId); this.active = true; move(e); e.preventDefault();
    });
    canvas.addEventListener("pointermove", (e) => { if (this.active) move(e); });
    const release = () => { this.active = false; this.x = 0; this.y = 0; this.draw(); };
    canvas.addEventListener("pointerup", release);
    canvas.addEventListener("pointercancel", release);
    canvas.addEventListener("lostpointercapture", release);
    this.release = release;
    this.draw();
  }

  draw() {
    const { ctx, canvas } = this, w = canvas.width, c = w / 2;
    ctx.clearRect(0, 0, w, w);
    ctx.strokeStyle = "#2b3540"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.arc(c, c, c - 3, 0, 2 * Math.PI); ctx.stroke();
    ctx.beginPath(); ctx.moveTo(c, 8); ctx.lineTo(c, w - 8); ctx.moveTo(8, c); ctx.lineTo(w - 8, c); ctx.stroke();
    ctx.fillStyle = this.active ? "#4cc2ff" : "#3b4a5a";
    ctx.beginPath(); ctx.arc(c + this.x * (c - 22), c + this.y * (c - 22), 20, 0, 2 * Math.PI); ctx.fill();
  }
}

const TELEOP_KEYS = { KeyW: ["forward", 1], KeyS: ["forward", -1], KeyA: ["left", 1], KeyD: ["left", -1],
  KeyQ: ["turn", 1], KeyE: ["turn", -1], KeyR: ["up", 1], KeyF: ["up", -1] };
const OBJECT_KEYS = { ArrowUp: ["north", 1], ArrowDown: ["north", -1], ArrowRight: ["east", 1], ArrowLeft: ["east", -1] };

class Keyboard {
  constructor() {
    this.down = new Set();
    const typing = (e) => e.target && ["INPUT", "SELECT", "TEXTAREA"].includes(e.target.tagName);
    window.addEventListener("keydown", (e) => {
      if (typing(e)) return;
      if (e.code in TELEOP_KEYS || e.code in OBJECT_KEYS) { this.down.add(e.code); e.preventDefault(); }
    });
    window.addEventListener("keyup", (e) => this.down.delete(e.code));
    window.addEventListener("blur", () => this.down.clear());
  }

  sum(table) {
    const out = {};
    for (const code of this.down) if (code in table) { const [k, v] = table[code]; out[k] = (out[k] || 0) + v; }
    return out;
  }
}

const DEADZONE = 0.12, DEADMAN_BUTTON = 4; // LB on the standard mapping

function gamepadSticks() {
  // {forward, left, up, turn} while the dead-man button is held on the first gamepad, else null.
  const pads = navigator.getGamepads ? navigator.getGamepads() : [];
  const pad = Array.from(pads || []).find((p) => p && p.connected);
  if (!pad) return { present: false, sticks: null };
  const held = pad.buttons[DEADMAN_BUTTON] && pad.buttons[DEADMAN_BUTTON].pressed;
  if (!held) return { present: true, sticks: null };
  const ax = (i) => { const v = pad.axes[i] || 0; return Math.abs(v) < DEADZONE ? 0 : v; };
  return { present: true, sticks: { turn: -ax(0), up: -ax(1), left: -ax(2), forward: -ax(3) } };
}

window.Stick = Stick; window.Keyboard = Keyboard; window.gamepadSticks = gamepadSticks;
window.TELEOP_KEYS = TELEOP_KEYS; window.OBJECT_KEYS = OBJECT_KEYS;
