// The model's exact boundary for the measuring tool: the faces of the stored
// file's NURBS JSON (POST /v1/conversions, format json: the same scene the
// renderer draws, double precision), their trim loops lifted onto the surfaces
// as 3D polylines, and the B-rep vertices among their points. A snap to a
// vertex gives S(u, v) at the loop's corner, evaluated in double, not a pixel.

import { sub, dot, length as norm } from './vec3.js';

// The knot span of u (Piegl & Tiller A2.1, FindSpan).
function findSpan(n, p, u, U) {
  if (u >= U[n + 1]) return n;
  if (u <= U[p]) return p;
  let low = p, high = n + 1, mid = (low + high) >> 1;
  while (u < U[mid] || u >= U[mid + 1]) {
    if (u < U[mid]) high = mid;
    else low = mid;
    mid = (low + high) >> 1;
  }
  return mid;
}

// The p + 1 non-zero basis functions at u (Piegl & Tiller A2.2, BasisFuns).
function basisFuns(i, u, p, U) {
  const N = [1], left = [], right = [];
  for (let j = 1; j <= p; j++) {
    left[j] = u - U[i + 1 - j];
    right[j] = U[i + j] - u;
    let saved = 0;
    for (let r = 0; r < j; r++) {
      const temp = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
  return N;
}

// S(u, v) of a face's surface as the NURBS JSON writes it (homogeneous
// control points, u-major): Piegl & Tiller A4.3 (SurfacePoint, rational).
export function surfacePoint(s, u, v) {
  const p = s.degree_u, q = s.degree_v;
  const su = findSpan(s.num_u - 1, p, u, s.knots_u), sv = findSpan(s.num_v - 1, q, v, s.knots_v);
  const Nu = basisFuns(su, u, p, s.knots_u), Nv = basisFuns(sv, v, q, s.knots_v);
  const h = [0, 0, 0, 0];
  for (let k = 0; k <= p; k++) {
    for (let l = 0; l <= q; l++) {
      const c = s.control_points[(su - p + k) * s.num_v + (sv - q + l)];
      const w = Nu[k] * Nv[l];
      for (let m = 0; m < 4; m++) h[m] += w * c[m];
    }
  }
  return [h[0] / h[3], h[1] / h[3], h[2] / h[3]];
}

// A loop point is a vertex where the boundary turns by more than this in 3D:
// a corner between two edges. Samples along one smooth edge turn by a few
// degrees at most (the loops follow the pcurves within the trim tolerance).
const VERTEX_TURN_DEG = 20;


// The face's loops as (u, v) polylines; an untrimmed face is bounded by its parameter box.
function faceLoops(f) {
  if (f.trim_loops.length) return f.trim_loops.map((l) => l.points);
  const [u0, u1] = f.u_range, [v0, v1] = f.v_range;
  return [[[u0, v0], [u1, v0], [u1, v1], [u0, v1]]];
}

// The loop points that are no corner but lie within about `tolerance` (the
// neighbouring cells of a grid that fine) of loop points of `faces` distinct
// faces (theirs included): a B-rep vertex joins at least three faces (two at
// most meet along one edge), which finds the vertices where edges meet
// tangentially (a slot's straight side and its round end), where the
// boundary does not turn. One point a face and cell.
function sharedPoints(points, tolerance, faces) {
  // cells: x -> y -> z -> Set of faces (numeric keys: string keys were most of the time on 120k points).
  const cells = new Map();
  const cellOf = (p) => [Math.floor(p[0] / tolerance), Math.floor(p[1] / tolerance), Math.floor(p[2] / tolerance)];
  const cellAt = (x, y, z) => cells.get(x)?.get(y)?.get(z);
  for (const pt of points) {
    const [x, y, z] = cellOf(pt.p);
    if (!cells.has(x)) cells.set(x, new Map());
    const cx = cells.get(x);
    if (!cx.has(y)) cx.set(y, new Map());
    const cy = cx.get(y);
    if (!cy.has(z)) cy.set(z, new Set());
    cy.get(z).add(pt.face);
  }
  const out = [];
  const taken = new Map();  // a cell's Set of faces -> the faces already given a point there
  for (const pt of points) {
    if (pt.corner) continue;
    const [x, y, z] = cellOf(pt.p), own = cellAt(x, y, z);
    if (!taken.has(own)) {
      const near = new Set();
      for (let dx = -1; dx <= 1; dx++)
        for (let dy = -1; dy <= 1; dy++)
          for (let dz = -1; dz <= 1; dz++) {
            const cell = cellAt(x + dx, y + dy, z + dz);
            if (cell) for (const face of cell) near.add(face);
          }
      taken.set(own, near.size >= faces ? new Set() : null);
    }
    const given = taken.get(own);
    if (given && !given.has(pt.face)) {
      given.add(pt.face);
      out.push(pt);
    }
  }
  return out;
}

// Loop points closer than this fraction of the model's size (and at least
// VERTEX_JOIN_MM) are one vertex: the faces' pcurves meet their shared vertex
// within the file's edge tolerance, which STEP writers keep well under it.
const VERTEX_JOIN_FRACTION = 1e-6, VERTEX_JOIN_MM = 1e-4;
const VERTEX_FACES = 3;

// A loop's segment is straight in (u, v) but may be a long curve in 3D (a
// cylinder's rim is one segment from u = 0 to 2 pi): it is split at its (u, v)
// midpoint while the surface's midpoint lies farther than this fraction of
// the model's size from the chord's, at most MAX_SPLITS deep. The chords only
// find the edge under the pointer; the picked point is on the surface.
const CHORD_SAGITTA_FRACTION = 1e-3, MAX_SPLITS = 8;

// Appends the points after `a` up to and including `b` to `chain`.
function subdivide(surface, a, b, sagitta, depth, chain) {
  const uv = [(a.uv[0] + b.uv[0]) / 2, (a.uv[1] + b.uv[1]) / 2];
  const m = { uv, p: surfacePoint(surface, uv[0], uv[1]) };
  const chordMid = [(a.p[0] + b.p[0]) / 2, (a.p[1] + b.p[1]) / 2, (a.p[2] + b.p[2]) / 2];
  if (depth > 0 && norm(sub(m.p, chordMid)) > sagitta) {
    subdivide(surface, a, m, sagitta, depth - 1, chain);
    subdivide(surface, m, b, sagitta, depth - 1, chain);
  } else {
    chain.push(b);
  }
}

// Vertices [{p, face}], edge segments [{a, b, uvA, uvB, face, surface,
// toleranceUv: the face's trim tolerance, how far its loops may be off the edges}] and
// every chord's end (`points`; a segment's ends are points[ia] and points[ib],
// so that a frame projects each point once) of the model, and how far a chord
// may be from its curve (`sagitta`, mm).
export function modelEdges(doc) {
  const vertices = [], segments = [], loopPoints = [], points = [];
  const cosTurn = Math.cos((VERTEX_TURN_DEG * Math.PI) / 180);
  const box = doc.bbox ? Math.hypot(...sub(doc.bbox.max, doc.bbox.min)) : 0;
  const sagitta = CHORD_SAGITTA_FRACTION * box;
  for (const f of doc.faces) {
    for (const loop of faceLoops(f)) {
      const pts = loop.map(([u, v]) => surfacePoint(f.surface, u, v));
      const n = pts.length;
      for (let i = 0; i < n; i++) {
        const j = (i + 1) % n;
        // The segment's image on the surface as chords within `sagitta` of it.
        const chain = [{ uv: loop[i], p: pts[i] }];
        subdivide(f.surface, chain[0], { uv: loop[j], p: pts[j] }, sagitta, MAX_SPLITS, chain);
        for (let k = 1; k < chain.length; k++) {
          const a = chain[k - 1], b = chain[k];
          if (!(norm(sub(b.p, a.p)) > 0)) continue;
          points.push(a.p, b.p);
          segments.push({ a: a.p, b: b.p, ia: points.length - 2, ib: points.length - 1, uvA: a.uv, uvB: b.uv, face: f.index,
            surface: f.surface, toleranceUv: f.trim_tolerance_uv || 0 });
        }
      }
      // The turn at each point, between the nearest distinct neighbours (a
      // degenerate edge, such as a sphere's pole, is a point in 3D).
      for (let i = 0; i < n; i++) {
        let back = null, ahead = null;
        for (let k = 1; k < n && !back; k++) { const d = sub(pts[i], pts[(i - k + n) % n]); if (norm(d) > 0) back = d; }
        for (let k = 1; k < n && !ahead; k++) { const d = sub(pts[(i + k) % n], pts[i]); if (norm(d) > 0) ahead = d; }
        const corner = !!(back && ahead && dot(back, ahead) / (norm(back) * norm(ahead)) < cosTurn);
        if (corner) vertices.push({ p: pts[i], face: f.index });
        loopPoints.push({ p: pts[i], face: f.index, corner });
      }
    }
  }
  vertices.push(...sharedPoints(loopPoints, Math.max(VERTEX_JOIN_MM, VERTEX_JOIN_FRACTION * box), VERTEX_FACES));
  return { vertices, segments, points, sagitta };
}
