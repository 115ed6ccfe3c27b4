// An edge point made exact: a point of a face's trim loop lies on the true
// edge only to within the loop's sampling tolerance; the edge is where the
// face's surface meets its neighbour's, so the point is moved onto both
// surfaces (Newton's method on the two tangent planes and the plane across
// the edge through the start, re-projected each step).

import { surfacePoint } from './model_edges.js';
import { sub, add, scale, dot, cross, length as norm } from './vec3.js';

// Central differences of S over this fraction of the parameter range: the
// truncation error (h^2) and the rounding (eps / h) are both about 1e-10 of the
// surface's size, far below what the point's projection needs.
const DIFF_STEP = 1e-5;
// Gauss-Newton steps of a point's projection onto a surface, and of the edge
// point's iteration; both converge quadratically from a start within a loop's
// sampling tolerance, in two or three steps.
const PROJECT_STEPS = 10, EDGE_STEPS = 10;
// Two faces meeting at less than this are nearly tangent along the edge (a
// fillet's side): their intersection is ill-conditioned there, so the loop
// point, within the sampling tolerance, stays.
const MIN_EDGE_ANGLE_DEG = 5;

function partials(s, u, v) {
  const hu = DIFF_STEP * (s.knots_u[s.num_u] - s.knots_u[s.degree_u]);
  const hv = DIFF_STEP * (s.knots_v[s.num_v] - s.knots_v[s.degree_v]);
  return {
    su: scale(sub(surfacePoint(s, u + hu, v), surfacePoint(s, u - hu, v)), 0.5 / hu),
    sv: scale(sub(surfacePoint(s, u, v + hv), surfacePoint(s, u, v - hv)), 0.5 / hv),
  };
}

// The point of surface s nearest p, from (u, v): {point, uv, normal} (Piegl &
// Tiller 6.1, point inversion, with the first derivatives only).
export function projectOnSurface(s, p, [u0, v0]) {
  let u = u0, v = v0;
  for (let k = 0; k < PROJECT_STEPS; k++) {
    const { su, sv } = partials(s, u, v), r = sub(p, surfacePoint(s, u, v));
    const a = dot(su, su), b = dot(su, sv), c = dot(sv, sv), det = a * c - b * b;
    if (!(det > 0)) break;
    const g1 = dot(su, r), g2 = dot(sv, r);
    const du = (c * g1 - b * g2) / det, dv = (a * g2 - b * g1) / det;
    u += du;
    v += dv;
    if (Math.hypot(du * Math.sqrt(a), dv * Math.sqrt(c)) < 1e-13 * (1 + norm(p))) break;
  }
  const { su, sv } = partials(s, u, v), n = cross(su, sv);
  return { point: surfacePoint(s, u, v), uv: [u, v], normal: scale(n, 1 / (norm(n) || 1)) };
}

// The point where faces a and b ({surface, uv}: the start's parameters on
// each) meet, nearest `start` across the edge, with the distance between its
// two surfaces' points (how exact it is); null where the faces are nearly
// tangent or the iteration does not settle.
export function exactEdgePoint(start, a, b) {
  let x = start, pa = null, pb = null;
  const minSin = Math.sin((MIN_EDGE_ANGLE_DEG * Math.PI) / 180);
  for (let k = 0; k < EDGE_STEPS; k++) {
    pa = projectOnSurface(a.surface, x, pa ? pa.uv : a.uv);
    pb = projectOnSurface(b.surface, x, pb ? pb.uv : b.uv);
    const t = cross(pa.normal, pb.normal);
    if (norm(t) < minSin) return null;
    // x on both tangent planes and on the plane across the edge through the start.
    const d1 = dot(pa.normal, pa.point), d2 = dot(pb.normal, pb.point), d3 = dot(t, start);
    const det = dot(pa.normal, cross(pb.normal, t));
    const next = scale(add(add(scale(cross(pb.normal, t), d1), scale(cross(t, pa.normal), d2)), scale(cross(pa.normal, pb.normal), d3)), 1 / det);
    const moved = norm(sub(next, x));
    x = next;
    if (moved < 1e-12 * (1 + norm(x))) break;
  }
  pa = projectOnSurface(a.surface, x, pa.uv);
  pb = projectOnSurface(b.surface, x, pb.uv);
  const residual = Math.max(norm(sub(pa.point, x)), norm(sub(pb.point, x)));
  return Number.isFinite(residual) ? { point: x, residual } : null;
}
