// The camera the page moves: eye, target and up in model units (as the API's
// `camera` option and the statistics' `camera` carry them), and the orbit, pan
// and zoom of a turntable viewer.

import { sub, add, scale, dot, cross, length, normalize } from './vec3.js';

// Rotation of v about the unit axis k by angle a (Rodrigues' formula).
function rotate(v, k, a) {
  const c = Math.cos(a), s = Math.sin(a);
  return add(add(scale(v, c), scale(cross(k, v), s)), scale(k, dot(k, v) * (1 - c)));
}

export class Camera {
  // projection: 'perspective' (fovDeg) or 'orthographic' (orthoHeight, the view's
  // height in model units), as the API's named views answer (orthographic by default).
  constructor(eye, target, up, fovDeg, projection = 'perspective', orthoHeight = 0) {
    this.eye = eye;
    this.target = target;
    this.up = up;
    this.fovDeg = fovDeg || 30;
    this.projection = projection;
    this.orthoHeight = orthoHeight || 2 * length(sub(target, eye)) * Math.tan((this.fovDeg * Math.PI) / 360);
  }

  static fromStatistics(c) {
    return new Camera(c.eye, c.target, c.up, c.fov_deg, c.projection || 'perspective', c.ortho_height);
  }

  // The `camera` render option.
  toOption() {
    const round = (v) => v.map((x) => Number(x.toPrecision(12)));
    const o = { eye: round(this.eye), target: round(this.target), up: round(this.up), projection: this.projection };
    if (this.projection === 'orthographic') o.ortho_height = Number(this.orthoHeight.toPrecision(12));
    else o.fov_deg = this.fovDeg;
    return o;
  }

  // Switches projection keeping what the view shows at the target the same size:
  // a perspective view of field fov at distance d shows 2 d tan(fov / 2) there.
  setProjection(projection) {
    if (projection === this.projection) return;
    const d = length(sub(this.eye, this.target));
    const tanHalf = Math.tan((this.fovDeg * Math.PI) / 360);
    if (projection === 'orthographic') {
      this.orthoHeight = 2 * d * tanHalf;
    } else {
      const dir = normalize(sub(this.eye, this.target));
      this.eye = add(this.target, scale(dir, this.orthoHeight / (2 * tanHalf)));
    }
    this.projection = projection;
  }

  // The view's height at the target, model units.
  viewHeight() {
    return this.projection === 'orthographic' ? this.orthoHeight
      : 2 * length(sub(this.target, this.eye)) * Math.tan((this.fovDeg * Math.PI) / 360);
  }

  basis() {
    const f = normalize(sub(this.target, this.eye));
    const r = normalize(cross(f, this.up));
    return { f, r, u: cross(r, f) };
  }

  // The pixel ray of the renderer's camera contract (renderer/camera.h) at the
  // continuous pixel position (px, py) of a width x height frame (pixel i spans
  // [i, i + 1)): {origin, dir}, dir of unit length, hit = origin + t dir, the t
  // of the z AOV.
  rayAt(px, py, width, height) {
    const { f, r, u } = this.basis();
    const sx = (2 * px / width - 1) * (width / height), sy = 1 - 2 * py / height;
    if (this.projection === 'orthographic')
      return { origin: add(this.eye, add(scale(r, 0.5 * this.orthoHeight * sx), scale(u, 0.5 * this.orthoHeight * sy))), dir: f };
    const tan = Math.tan((this.fovDeg * Math.PI) / 360);
    return { origin: this.eye, dir: normalize(add(f, add(scale(r, tan * sx), scale(u, tan * sy)))) };
  }

  // Where a point p falls in a width x height frame: a function of p giving {x, y}
  // (continuous pixel position, as rayAt takes it) and t, its distance along
  // that ray. The basis is computed once: measuring projects every edge point.
  projector(width, height) {
    const { f, r, u } = this.basis(), aspect = width / height;
    const half = 0.5 * this.orthoHeight, tan = Math.tan((this.fovDeg * Math.PI) / 360);
    const ortho = this.projection === 'orthographic', eye = this.eye;
    return (p) => {
      const d = sub(p, eye), zc = dot(f, d);
      const k = ortho ? 1 / half : 1 / (zc * tan);
      const t = ortho ? zc : Math.sign(zc) * length(d);
      return { x: (dot(r, d) * k / aspect + 1) * 0.5 * width, y: (1 - dot(u, d) * k) * 0.5 * height, t };
    };
  }

  // The size of one pixel of a frame `height` pixels high, at distance t, model units.
  pixelSize(t, height) {
    return this.projection === 'orthographic' ? this.orthoHeight / height
      : (2 * t * Math.tan((this.fovDeg * Math.PI) / 360)) / height;
  }

  // Turntable orbit about the target: yaw about the up vector, pitch about the
  // camera's right axis (kept away from the poles so that up stays defined).
  orbit(yaw, pitch) {
    const { r } = this.basis();
    const k = normalize(this.up);
    let offset = sub(this.eye, this.target);
    offset = rotate(offset, k, -yaw);
    const right = rotate(r, k, -yaw);
    const pitched = rotate(offset, right, -pitch);
    const cosToUp = dot(normalize(pitched), k);
    if (Math.abs(cosToUp) < 0.995) offset = pitched;
    this.eye = add(this.target, offset);
    this.up = k;
  }

  // Moves eye and target together by a fraction of the view's height.
  pan(dxFraction, dyFraction) {
    const { r, u } = this.basis();
    const viewHeight = this.viewHeight();
    const move = add(scale(r, -dxFraction * viewHeight), scale(u, dyFraction * viewHeight));
    this.eye = add(this.eye, move);
    this.target = add(this.target, move);
  }

  // factor < 1 moves closer (an orthographic view narrows instead: moving its
  // eye would change nothing on screen).
  zoom(factor) {
    const f = Math.min(Math.max(factor, 0.2), 5);
    if (this.projection === 'orthographic') {
      this.orthoHeight *= f;
      return;
    }
    const offset = sub(this.eye, this.target);
    this.eye = add(this.target, scale(offset, f));
  }
}
