// Mouse, touch and keyboard on the image: drag orbits, shift-drag or
// right-drag (or two fingers) pans, wheel or pinch zooms; arrow keys orbit,
// shift+arrows pan, +/- zoom. Calls move(camera change) for every step and
// settle() once the pointer stops (released, or the wheel/keys idle).

const SETTLE_MS = 200;     // wheel and keys: a pause this long ends the gesture
const ORBIT_PER_PX = 0.01; // radians per CSS pixel of drag
const KEY_ORBIT = Math.PI / 18;

export function bindInteraction(canvas, { move, settle, hover }) {
  const pointers = new Map();  // pointerId -> {x, y}
  let mode = null;             // 'orbit' | 'pan' while dragging
  let pinch = null;            // {distance, x, y} with two pointers
  let settleTimer = 0;

  const settleSoon = () => {
    clearTimeout(settleTimer);
    settleTimer = setTimeout(settle, SETTLE_MS);
  };
  const size = () => canvas.getBoundingClientRect();

  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    mode = e.button === 2 || e.shiftKey ? 'pan' : 'orbit';
    if (pointers.size === 2) {
      const [a, b] = [...pointers.values()];
      pinch = { distance: Math.hypot(a.x - b.x, a.y - b.y), x: (a.x + b.x) / 2, y: (a.y + b.y) / 2 };
    }
    canvas.classList.add('dragging');
    e.preventDefault();
  });
  canvas.addEventListener('pointermove', (e) => {
    const last = pointers.get(e.pointerId);
    if (!last) {
      hover(e);
      return;
    }
    const dx = e.clientX - last.x, dy = e.clientY - last.y;
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    if (pointers.size === 2 && pinch) {
      const [a, b] = [...pointers.values()];
      const distance = Math.hypot(a.x - b.x, a.y - b.y), cx = (a.x + b.x) / 2, cy = (a.y + b.y) / 2;
      const h = size().height || 1;
      move((c) => {
        c.zoom(pinch.distance / (distance || 1));
        c.pan((cx - pinch.x) / h, (cy - pinch.y) / h);
      });
      pinch = { distance, x: cx, y: cy };
    } else if (pointers.size === 1 && (dx || dy)) {
      const h = size().height || 1;
      if (mode === 'pan') move((c) => c.pan(dx / h, dy / h));
      else move((c) => c.orbit(dx * ORBIT_PER_PX, dy * ORBIT_PER_PX));
    }
  });
  const release = (e) => {
    if (!pointers.delete(e.pointerId)) return;
    if (pointers.size < 2) pinch = null;
    if (pointers.size === 0) {
      mode = null;
      canvas.classList.remove('dragging');
      settle();
    }
  };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);

  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    move((c) => c.zoom(Math.exp(e.deltaY * 0.0015)));
    settleSoon();
  }, { passive: false });

  canvas.addEventListener('keydown', (e) => {
    const step = {
      ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1],
    }[e.key];
    if (step && e.shiftKey) move((c) => c.pan(step[0] * 0.05, step[1] * 0.05));
    else if (step) move((c) => c.orbit(step[0] * KEY_ORBIT, step[1] * KEY_ORBIT));
    else if (e.key === '+' || e.key === '=') move((c) => c.zoom(0.85));
    else if (e.key === '-' || e.key === '_') move((c) => c.zoom(1 / 0.85));
    else return;
    e.preventDefault();
    settleSoon();
  });
}
