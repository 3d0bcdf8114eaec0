#include "StepLanes.hpp"

#include <cmath>

#include "RotationSeries.hpp"
#include "SimdDispatch.hpp"
#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/events/EventSchedule.hpp"

// The loops below over kLanes lanes are written for the vectoriser (no calls, selects instead of branches);
// the few lanes of opposite directions (the hinge) or of large turns (sin and cos) are finished by the scalar
// functions in between.
// This file is compiled with -fno-math-errno (sqrt vectorises) and -ffp-contract=off (no FMA: the AVX2 and
// baseline code give the same bits).

namespace hair_sim {
namespace lanes {

namespace {

constexpr int W = kLanes;

// N lanes of doubles (V) and their masks (M, 0 or -1 per lane) are GCC vector types: every operation works
// on all lanes at once. The AVX2 code takes N = 4 (one ymm register), the baseline code N = 2 (one xmm),
// twice per block: the lanes never mix, so the results are the same.
static_assert(sizeof(long) == 8, "lane masks are 64-bit");
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles (loadVec3, storeVec3)");
template <int N>
struct VecTypes;
template <>
struct VecTypes<2> {
  typedef double V __attribute__((vector_size(16)));
  typedef long M __attribute__((vector_size(16)));
  typedef int I __attribute__((vector_size(8)));            // point indices
  typedef unsigned char C __attribute__((vector_size(2)));  // flags
};
template <>
struct VecTypes<4> {
  typedef double V __attribute__((vector_size(32)));
  typedef long M __attribute__((vector_size(32)));
  typedef int I __attribute__((vector_size(16)));
  typedef unsigned char C __attribute__((vector_size(4)));
};

template <class V>
HAIR_SIM_ALWAYS_INLINE V vsqrt(V x) {
  V r;
  for (int l = 0; l < static_cast<int>(sizeof(V) / sizeof(double)); ++l) r[l] = __builtin_sqrt(x[l]);
  return r;
}
template <class V>
HAIR_SIM_ALWAYS_INLINE V splat(double x) {
  return V{} + x;
}
template <class M, class V>
HAIR_SIM_ALWAYS_INLINE V sel(M m, V a, V b) {
  return m ? a : b;
}
/// Whether any lane of the mask is set (an OR of the halves, then of the lanes).
template <class M>
HAIR_SIM_ALWAYS_INLINE bool anyLane(M m) {
  if constexpr (sizeof(M) == 32) {
    typedef long M2 __attribute__((vector_size(16)));
    const M2 lo = {m[0], m[1]}, hi = {m[2], m[3]};
    const M2 o = lo | hi;
    return (o[0] | o[1]) != 0;
  } else {
    return (m[0] | m[1]) != 0;
  }
}

/// atan2(s, c) / s for s > 0: the hinge's angle over its sine, within an ulp or two of std::atan2(s, c) / s.
/// The Cephes library's atan on the ratio reduced to |x| <= 0.66 (x = s / |c|; -|c| / s above tan(3 pi / 8),
/// (s - |c|) / (s + |c|) above 0.66: one division for all three) and its rational approximation; plain
/// arithmetic, so every lane and every instruction set give the same bits. Three divisions, no series
/// beside it.
template <class V>
HAIR_SIM_ALWAYS_INLINE V vatan2OverS(V s, V c) {
  typedef decltype(V{} < V{}) M;
  const V ac = sel(c < 0.0, -c, c);
  const M big = s > 2.414213562373095 * ac;  // tan(3 pi / 8)
  const M mid = ~big & (s > 0.66 * ac);
  const double kMoreBits = 6.123233995736765886130e-17;
  const V xr = sel(big, -ac, sel(mid, s - ac, s)) / sel(big, s, sel(mid, s + ac, ac));
  const V y0 = sel(big, splat<V>(1.5707963267948966), sel(mid, splat<V>(0.7853981633974483), splat<V>(0.0)));
  const V more = sel(big, splat<V>(kMoreBits), sel(mid, splat<V>(0.5 * kMoreBits), splat<V>(0.0)));
  const V z = xr * xr;
  const V pp =
      (((-8.750608600031904122785e-1 * z + -1.615753718733365076637e1) * z + -7.500855792314704667340e1) * z +
       -1.228866684490136173410e2) *
          z +
      -6.485021904942025371773e1;
  const V qq =
      ((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z + 4.328810604912902668951e2) *
           z +
       4.853903996359136964868e2) *
          z +
      1.945506571482613964425e2;
  const V a = y0 + (more + (xr * (z * pp / qq) + xr));
  return sel(c < 0.0, 3.141592653589793 - a, a) / s;
}

/// Does the straight path q0 -> q1 (sphere space) enter the unit sphere from outside? (Lane form of the
/// Simulator's pathEntersUnitSphere.)
template <class V>
HAIR_SIM_ALWAYS_INLINE auto pathEnters(V q0x, V q0y, V q0z, V q1x, V q1y, V q1z) -> decltype(V{} < V{}) {
  typedef decltype(V{} < V{}) M;
  const V c = (q0x * q0x + q0y * q0y + q0z * q0z) - 1.0;
  const V dx = q1x - q0x, dy = q1y - q0y, dz = q1z - q0z;
  const V a = dx * dx + dy * dy + dz * dz;
  const V b = q0x * dx + q0y * dy + q0z * dz;
  const V disc = b * b - a * c;
  // t = (-b - sqrt(disc)) / a <= 1 as -b - a <= sqrt(disc), like the Simulator's pathEntersUnitSphere.
  const V lhs = -b - a;
  const M a_ok = a >= 1e-300;
  return (c > 0.0) & a_ok & (b < 0.0) & (disc >= 0.0) & ((lhs <= 0.0) | (lhs * lhs <= disc));
}

/// Lane l of the vector: base[idx[l] * stride + c], built from scalars in registers (not lane by lane
/// through memory). A function, not a lambda of blockBody: a lambda does not take its enclosing function's
/// target("avx2"), so where the compiler left it out of line (clang with ASan and UBSan) it returned its
/// 32-byte vector by the baseline's ABI to an AVX2 caller that read it from a register: garbage, NaN hair
/// (fuzz_yaml). Always inlined, a function takes the caller's instruction set: every function here that
/// passes or returns a vector is HAIR_SIM_ALWAYS_INLINE, and no lambda does. (-Wpsabi cannot police this:
/// it warns about every such function, inlined or not, so it is off for this file.)
template <int N, class V>
HAIR_SIM_ALWAYS_INLINE V gatherLanes(const double* base, int stride, int c, const int* idx) {
  if constexpr (N == 4)
    return V{base[idx[0] * stride + c], base[idx[1] * stride + c], base[idx[2] * stride + c],
             base[idx[3] * stride + c]};
  else
    return V{base[idx[0] * stride + c], base[idx[1] * stride + c]};
}
/// Coordinate c of the Vec3 at idx[l] of a, lane by lane.
template <int N, class V>
HAIR_SIM_ALWAYS_INLINE V gatherVec3(const Vec3* a, int c, const int* idx) {
  return gatherLanes<N, V>(reinterpret_cast<const double*>(a), 3, c, idx);
}
/// N consecutive doubles (a block's constant in lane order).
template <class V>
HAIR_SIM_ALWAYS_INLINE V loadLanes(const double* at) {
  V v;
  __builtin_memcpy(&v, at, sizeof(V));
  return v;
}
static_assert(LaneBody::kCopies == kLanes, "a LaneBody value is stored once per lane of a block");
/// The first lanes of a LaneBody value (stored once per lane): a vector read from memory.
template <class T, class E>
HAIR_SIM_ALWAYS_INLINE T lanesOf(const E* at) {
  static_assert(sizeof(T) <= sizeof(E) * LaneBody::kCopies, "a LaneBody value has kCopies lanes");
  T v;
  __builtin_memcpy(&v, at, sizeof(T));
  return v;
}
/// x, y and z of the Vec3s at idx[l] of a, lane by lane; with `pairs` (every lane active, lanes 2m and 2m + 1
/// reading consecutive points, as the two columns of a strip do) by whole loads and shuffles instead of a
/// load per value: the same values. (Two consecutive Vec3s are six packed doubles.)
template <int N, class V>
HAIR_SIM_ALWAYS_INLINE void loadVec3(const Vec3* a, const int* idx, bool pairs, V& x, V& y, V& z) {
  if (!pairs) {
    x = gatherVec3<N, V>(a, 0, idx), y = gatherVec3<N, V>(a, 1, idx), z = gatherVec3<N, V>(a, 2, idx);
    return;
  }
  const double* p = reinterpret_cast<const double*>(a + idx[0]);
  if constexpr (N == 4) {
    const double* q = reinterpret_cast<const double*>(a + idx[2]);
    const V lo = loadLanes<V>(p), hi = loadLanes<V>(q);         // x0 y0 z0 x1, x2 y2 z2 x3
    const V tail = {p[4], p[5], q[4], q[5]};                    // y1 z1 y3 z3
    const V mix = __builtin_shufflevector(lo, hi, 1, 5, 2, 6);  // y0 y2 z0 z2
    x = __builtin_shufflevector(lo, hi, 0, 3, 4, 7);
    y = __builtin_shufflevector(mix, tail, 0, 4, 1, 6);
    z = __builtin_shufflevector(mix, tail, 2, 5, 3, 7);
  } else {
    const V a0 = loadLanes<V>(p), a1 = loadLanes<V>(p + 2), a2 = loadLanes<V>(p + 4);  // x0 y0, z0 x1, y1 z1
    x = __builtin_shufflevector(a0, a1, 0, 3);
    y = __builtin_shufflevector(a0, a2, 1, 2);
    z = __builtin_shufflevector(a1, a2, 0, 3);
  }
}
/// The Vec3 (x[l], y[l], z[l]) to a[idx[l]] for the lanes with idx[l] >= 0; with `pairs` (as loadVec3's) by
/// shuffles and whole stores.
template <int N, class V>
HAIR_SIM_ALWAYS_INLINE void storeVec3(Vec3* a, const int* idx, bool pairs, V x, V y, V z) {
  if (!pairs) {
    for (int l = 0; l < N; ++l)
      if (idx[l] >= 0) a[idx[l]] = Vec3(x[l], y[l], z[l]);
    return;
  }
  double* p = reinterpret_cast<double*>(a + idx[0]);
  if constexpr (N == 4) {
    double* q = reinterpret_cast<double*>(a + idx[2]);
    const V xy = __builtin_shufflevector(x, y, 0, 4, 2, 6);  // x0 y0 x2 y2
    const V zx = __builtin_shufflevector(z, x, 0, 5, 2, 7);  // z0 x1 z2 x3
    const V lo = __builtin_shufflevector(xy, zx, 0, 1, 4, 5);
    const V hi = __builtin_shufflevector(xy, zx, 2, 3, 6, 7);
    const V yz = __builtin_shufflevector(y, z, 1, 5, 3, 7);  // y1 z1 y3 z3
    __builtin_memcpy(p, &lo, sizeof(V));
    __builtin_memcpy(q, &hi, sizeof(V));
    p[4] = yz[0], p[5] = yz[1], q[4] = yz[2], q[5] = yz[3];
  } else {
    const V s0 = __builtin_shufflevector(x, y, 0, 2);
    const V s1 = __builtin_shufflevector(z, x, 0, 3);
    const V s2 = __builtin_shufflevector(y, z, 1, 3);
    __builtin_memcpy(p, &s0, sizeof(V));
    __builtin_memcpy(p + 2, &s1, sizeof(V));
    __builtin_memcpy(p + 4, &s2, sizeof(V));
  }
}

/// Lanes l0 .. l0 + N - 1 of the block; have_before = job.have_before.
template <int N, bool have_before>
HAIR_SIM_ALWAYS_INLINE void blockBody(BlockJob& job, int l0) {
  typedef typename VecTypes<N>::V V;
  typedef typename VecTypes<N>::M M;
  const double dt = job.dt, k = job.k, gamma = job.gamma, drag = job.drag;
  const double max_step = job.max_angle_step, cos_max_bend = job.cos_max_bend;
  const double* f0 = job.force0;
  const double* fm = job.force_mid;
  const double* fv = job.force_vel;

  V px, py, pz;  // pivot: the parent's new position
  // The parent's position at the start of the substep: the segment's midpoint then is op + d/2 n, bit for bit
  // the midpoint the last substep computed (as px + d/2 k), as every path computes it (stepStrip's
  // midAtStart).
  V opx, opy, opz;
  V q0 = splat<V>(1.0), q1 = splat<V>(0.0), q2 = splat<V>(0.0), q3 = splat<V>(0.0), q4 = splat<V>(1.0),
    q5 = splat<V>(0.0), q6 = splat<V>(0.0), q7 = splat<V>(0.0),
    q8 = splat<V>(1.0);  // rotation of the parent from its styled frame
  M flag = M{} & 0;
  M first_row = M{} & 0;        // the first row flagged, per lane (0: none yet)
  V max_rate2 = splat<V>(0.0);  // as std::max keeps it (a NaN never enters)
  for (int l = 0; l < N; ++l) {
    const int i0 = job.point[l0 + l];
    const Vec3 p = i0 >= 0 ? job.positions[i0] : Vec3::Zero();
    px[l] = p.x(), py[l] = p.y(), pz[l] = p.z();
  }
  opx = px, opy = py, opz = pz;  // (a root never moves)

  for (int r = 1; r < job.rows; ++r) {
    const int* pt = job.point + r * W + l0;
    V nx, ny, nz, vx, vy, vz, wx, wy, wz, fx, fy, fz, ux, uy, uz, sx, sy, sz, mx, my, mz, ex, ey, ez, d, ii;
    // The lanes with a point in this row (from the row's N point indices in one vector).
    typedef typename VecTypes<N>::I I;
    I row_points;
    __builtin_memcpy(&row_points, pt, sizeof(I));
    const M active = __builtin_convertvector(row_points >= 0, M);
    if (!anyLane(active)) break;
    const bool all_active = !anyLane(~active);
    bool pairs = all_active;
    for (int l = 0; l < N; l += 2) pairs = pairs && pt[l + 1] == pt[l] + 1;
    // The points to read: with pairs, pt itself (loadVec3 reads lanes 0 and 2); else lane by lane, an idle
    // lane reading point 0 (any point) and taking the idle values below instead.
    int idle_safe[N];
    const int* idx = pt;
    if (!pairs) {
      for (int l = 0; l < N; ++l) idle_safe[l] = pt[l] >= 0 ? pt[l] : 0;
      idx = idle_safe;
    }
    loadVec3<N>(job.direction, idx, pairs, nx, ny, nz);
    loadVec3<N>(job.velocity, idx, pairs, vx, vy, vz);
    loadVec3<N>(job.rate, idx, pairs, wx, wy, wz);
    loadVec3<N>(job.spring_force, idx, pairs, fx, fy, fz);
    const double* k_row = job.constants + static_cast<std::ptrdiff_t>(r) * kConstants * W + l0;
    ux = loadLanes<V>(k_row + 0 * W), uy = loadLanes<V>(k_row + 1 * W), uz = loadLanes<V>(k_row + 2 * W);
    sx = loadLanes<V>(k_row + 3 * W), sy = loadLanes<V>(k_row + 4 * W), sz = loadLanes<V>(k_row + 5 * W);
    loadVec3<N>(job.positions, idx, pairs, ex, ey, ez);
    d = loadLanes<V>(k_row + 6 * W);
    ii = loadLanes<V>(k_row + 7 * W);
    const V hd = 0.5 * d;
    mx = opx + hd * nx, my = opy + hd * ny, mz = opz + hd * nz;
    if (!all_active) {  // an idle lane: a still vertical segment, never written back
      const V zero = splat<V>(0.0), one = splat<V>(1.0);
      nx = sel(active, nx, zero), ny = sel(active, ny, zero), nz = sel(active, nz, one);
      vx = sel(active, vx, zero), vy = sel(active, vy, zero), vz = sel(active, vz, zero);
      wx = sel(active, wx, zero), wy = sel(active, wy, zero), wz = sel(active, wz, zero);
      fx = sel(active, fx, zero), fy = sel(active, fy, zero), fz = sel(active, fz, zero);
      mx = sel(active, mx, px), my = sel(active, my, py), mz = sel(active, mz, pz + 0.5);
      ex = sel(active, ex, px), ey = sel(active, ey, py), ez = sel(active, ez, pz + 1.0);
    }

    // (6) the force at the segment's midpoint c (the new pivot, the old direction) with its velocity v:
    // d (force0 + force_mid c + force_vel v + drag turbulence(c)) + the springs' force
    // (Simulator::StepFrame).
    const V cx = px + hd * nx, cy = py + hd * ny, cz = pz + hd * nz;
    V Fx = (f0[0] + (fm[0] * cx + fm[1] * cy + fm[2] * cz)) + (fv[0] * vx + fv[1] * vy + fv[2] * vz);
    V Fy = (f0[1] + (fm[3] * cx + fm[4] * cy + fm[5] * cz)) + (fv[3] * vx + fv[4] * vy + fv[5] * vz);
    V Fz = (f0[2] + (fm[6] * cx + fm[7] * cy + fm[8] * cz)) + (fv[6] * vx + fv[7] * vy + fv[8] * vz);
    if (job.turbulence) {  // at world points, lane by lane
      V tx = splat<V>(0.0), ty = splat<V>(0.0), tz = splat<V>(0.0);
      for (int l = 0; l < N; ++l) {
        if (pt[l] < 0) continue;
        const Vec3 t =
            *job.head_rotation_inverse * job.turbulence->at(*job.head_pose * Vec3(cx[l], cy[l], cz[l]));
        tx[l] = t.x(), ty[l] = t.y(), tz[l] = t.z();
      }
      Fx = Fx + drag * tx, Fy = Fy + drag * ty, Fz = Fz + drag * tz;
    }
    Fx = d * Fx + fx, Fy = d * Fy + fy, Fz = d * Fz + fz;
    // (4)-(5) its moment at the lever d/2.
    V Mx = hd * (ny * Fz - nz * Fy);
    V My = hd * (nz * Fx - nx * Fz);
    V Mz = hd * (nx * Fy - ny * Fx);
    // (3) the hinge: rest direction carried by the parent, rotationVectorBetween(rest, n) in lanes (the lanes
    // of opposite directions by the scalar function).
    const V restx = q0 * ux + q1 * uy + q2 * uz;
    const V resty = q3 * ux + q4 * uy + q5 * uz;
    const V restz = q6 * ux + q7 * uy + q8 * uz;
    const V axx = resty * nz - restz * ny, axy = restz * nx - restx * nz, axz = restx * ny - resty * nx;
    const V c = restx * nx + resty * ny + restz * nz;
    const V s2 = axx * axx + axy * axy + axz * axz;
    // The angle atan2(s, c) over s by vatan2OverS (s > 1e-12); a zero rotation for s <= 1e-12, c > 0;
    // opposite directions (s <= 1e-12, c <= 0) by the scalar function.
    const V sn = vsqrt(s2);
    const M has_axis = sn > 1e-12;
    const V scale = sel(has_axis, vatan2OverS(sel(has_axis, sn, splat<V>(1.0)), c), splat<V>(0.0));
    const M opposite = ~has_axis & ~(c > 0.0);
    V hx = axx * scale, hy = axy * scale, hz = axz * scale;
    if (anyLane(opposite))
      for (int l = 0; l < N; ++l)
        if (opposite[l]) {
          const Vec3 h = rotationVectorBetween(Vec3(restx[l], resty[l], restz[l]), Vec3(nx[l], ny[l], nz[l]));
          hx[l] = h.x(), hy[l] = h.y(), hz[l] = h.z();
        }

    // (7): the new rate w (without a part along n, limited to max_angle_step) and the new direction,
    // rotatePerpendicular(w, n) by its series for the small turns (the other lanes by the scalar function).
    Mx = Mx - k * hx, My = My - k * hy, Mz = Mz - k * hz;  // (both terms are perpendicular to n)
    const V keep = 1.0 - gamma * dt * ii, push = (dt * dt) * ii;
    V Wx = wx * keep + push * Mx, Wy = wy * keep + push * My, Wz = wz * keep + push * Mz;
    const V wn = Wx * nx + Wy * ny + Wz * nz;
    Wx = Wx - wn * nx, Wy = Wy - wn * ny, Wz = Wz - wn * nz;
    const V ww = Wx * Wx + Wy * Wy + Wz * Wz;
    const V step_angle = vsqrt(ww);
    const M over = step_angle > max_step;
    V a2 = ww;            // |w|^2 of the new rate
    if (anyLane(over)) {  // (the division only when some lane is over the limit)
      const V limit = max_step / sel(over, step_angle, splat<V>(1.0));
      Wx = sel(over, Wx * limit, Wx), Wy = sel(over, Wy * limit, Wy), Wz = sel(over, Wz * limit, Wz);
      a2 = sel(over, Wx * Wx + Wy * Wy + Wz * Wz, ww);
    }
    max_rate2 = sel(active & (max_rate2 < a2), a2, max_rate2);
    const M small = a2 < 0.01;
    const M tiny = a2 < 1e-24;
    const V crx = Wy * nz - Wz * ny, cry = Wz * nx - Wx * nz, crz = Wx * ny - Wy * nx;
    V co, sa;
    series::rotationCosSin(a2, co, sa);
    V bx = nx * co + crx * sa, by = ny * co + cry * sa, bz = nz * co + crz * sa;
    bx = sel(tiny, nx + crx, bx), by = sel(tiny, ny + cry, by), bz = sel(tiny, nz + crz, bz);
    const V len = vsqrt(bx * bx + by * by + bz * bz);
    V kx = bx / len, ky = by / len, kz = bz / len;
    if (anyLane(~small))
      for (int l = 0; l < N; ++l)
        if (!small[l]) {
          const Vec3 next =
              rotatePerpendicular(Vec3(Wx[l], Wy[l], Wz[l]), Vec3(nx[l], ny[l], nz[l])).normalized();
          kx[l] = next.x(), ky[l] = next.y(), kz[l] = next.z();
        }

    // The bend limit (a lane over it goes to the exact step), the new end, and the next segment's rest
    // frame Q = minimalRotation(Q styled, next) Q = (c I + [v]x + v h^T) Q, v = Q styled x next, h = v / (1 +
    // c).
    const V bend = restx * kx + resty * ky + restz * kz;
    const V nex = px + d * kx, ney = py + d * ky, nez = pz + d * kz;
    const M bent = (bend < cos_max_bend) & active;  // (kPointBend)
    M bad = M{} & 0;                                // a degenerate rest frame below
    if (r + 1 < job.rows) {
      const V ax = q0 * sx + q1 * sy + q2 * sz;
      const V ay = q3 * sx + q4 * sy + q5 * sz;
      const V az = q6 * sx + q7 * sy + q8 * sz;
      const V cq = ax * kx + ay * ky + az * kz;
      bad = cq < -1.0 + 1e-9;
      const V vx1 = ay * kz - az * ky, vy1 = az * kx - ax * kz, vz1 = ax * ky - ay * kx;
      const V den = sel(1.0 + cq > 1e-300, 1.0 + cq, splat<V>(1.0));
      const V hx1 = vx1 / den, hy1 = vy1 / den, hz1 = vz1 / den;
      const V r00 = vx1 * hx1 + cq, r01 = vx1 * hy1 - vz1, r02 = vx1 * hz1 + vy1;
      const V r10 = vy1 * hx1 + vz1, r11 = vy1 * hy1 + cq, r12 = vy1 * hz1 - vx1;
      const V r20 = vz1 * hx1 - vy1, r21 = vz1 * hy1 + vx1, r22 = vz1 * hz1 + cq;
      const V n0 = r00 * q0 + r01 * q3 + r02 * q6, n1 = r00 * q1 + r01 * q4 + r02 * q7,
              n2 = r00 * q2 + r01 * q5 + r02 * q8;
      const V n3 = r10 * q0 + r11 * q3 + r12 * q6, n4 = r10 * q1 + r11 * q4 + r12 * q7,
              n5 = r10 * q2 + r11 * q5 + r12 * q8;
      const V n6 = r20 * q0 + r21 * q3 + r22 * q6, n7 = r20 * q1 + r21 * q4 + r22 * q7,
              n8 = r20 * q2 + r21 * q5 + r22 * q8;
      q0 = n0, q1 = n1, q2 = n2, q3 = n3, q4 = n4, q5 = n5, q6 = n6, q7 = n7, q8 = n8;
    }
    M full = bad & active;  // this row's own step again (kPointFull)
    M hit = M{} & 0;        // the bodies in the way of this row's free step (kPointBodies)

    // Bodies: the quick reject of Simulator::prepareBodies, then for the bodies within reach its exact
    // tests: the end inside now (reaction constraint), or the new segment / the end's path over the
    // substep not clear of the body (Simulator::clearOf): the exact step decides.
    // With the body's last place: the reach of the segment and of the end's path, max(|prev end - pivot|, d).
    // Then one test is stronger than both of prepareBodies' (D > R + d, and D (1 - motion) > R + (|prev end
    // - pivot| + shift)(1 + motion)): a body it rejects, they reject too, so the flags are the same.
    V reach = d;
    if (have_before) {
      const V gx1 = ex - px, gy1 = ey - py, gz1 = ez - pz;
      const V reach_prev = vsqrt(gx1 * gx1 + gy1 * gy1 + gz1 * gz1);
      reach = sel(reach_prev > d, reach_prev, d);
    }
    for (int b = 0; b < job.body_count; ++b) {
      const LaneBody& B = job.bodies[b];
      const V dx = px - lanesOf<V>(B.centre[0]), dy = py - lanesOf<V>(B.centre[1]),
              dz = pz - lanesOf<V>(B.centre[2]);
      const V dist2 = dx * dx + dy * dy + dz * dz;
      M far;
      if (have_before) {
        const V lim = lanesOf<V>(B.bound_radius) + (reach + lanesOf<V>(B.shift)) * lanesOf<V>(B.grow);
        far = (dist2 * lanesOf<V>(B.keep2) > lim * lim) & lanesOf<M>(B.slow);
      } else {
        const V rch = lanesOf<V>(B.bound_radius) + d;
        far = dist2 > rch * rch;
      }
      const M reach = ~far & active;
      if (!anyLane(reach)) continue;
      const double(*S)[LaneBody::kCopies] = B.sinv;
      const double(*Sb)[LaneBody::kCopies] = B.sinv_before;
      const V qx = lanesOf<V>(S[0]) * dx + lanesOf<V>(S[1]) * dy + lanesOf<V>(S[2]) * dz;
      const V qy = lanesOf<V>(S[3]) * dx + lanesOf<V>(S[4]) * dy + lanesOf<V>(S[5]) * dz;
      const V qz = lanesOf<V>(S[6]) * dx + lanesOf<V>(S[7]) * dy + lanesOf<V>(S[8]) * dz;
      const V n2 = qx * qx + qy * qy + qz * qz;
      const M pivot_inside = n2 < 1.0;
      // (No sphere-space bound before the exact tests: where prepareBodies' bound -- |q| > 1 + d / smallest
      // radius + 1e-9 and the previous end within |q| - 1 - 1e-9 of q -- rejects a lane, the end now, the new
      // end, the segment and the end's path all lie in a ball about q outside the unit sphere, so the tests
      // below find nothing there either: the same flags.)
      V bx1 = splat<V>(0.0), by1 = splat<V>(0.0), bz1 = splat<V>(0.0);
      if (have_before) {
        const V ddx = ex - lanesOf<V>(B.centre_before[0]), ddy = ey - lanesOf<V>(B.centre_before[1]),
                ddz = ez - lanesOf<V>(B.centre_before[2]);
        bx1 = lanesOf<V>(Sb[0]) * ddx + lanesOf<V>(Sb[1]) * ddy + lanesOf<V>(Sb[2]) * ddz;
        by1 = lanesOf<V>(Sb[3]) * ddx + lanesOf<V>(Sb[4]) * ddy + lanesOf<V>(Sb[5]) * ddz;
        bz1 = lanesOf<V>(Sb[6]) * ddx + lanesOf<V>(Sb[7]) * ddy + lanesOf<V>(Sb[8]) * ddz;
      }
      // The end now (reaction constraint while inside) and the new end, in sphere space.
      const V snx = lanesOf<V>(S[0]) * nx + lanesOf<V>(S[1]) * ny + lanesOf<V>(S[2]) * nz;
      const V sny = lanesOf<V>(S[3]) * nx + lanesOf<V>(S[4]) * ny + lanesOf<V>(S[5]) * nz;
      const V snz = lanesOf<V>(S[6]) * nx + lanesOf<V>(S[7]) * ny + lanesOf<V>(S[8]) * nz;
      const V cx1 = qx + d * snx, cy1 = qy + d * sny, cz1 = qz + d * snz;
      const M inside_now = cx1 * cx1 + cy1 * cy1 + cz1 * cz1 < 1.0;
      const V skx = lanesOf<V>(S[0]) * kx + lanesOf<V>(S[1]) * ky + lanesOf<V>(S[2]) * kz;
      const V sky = lanesOf<V>(S[3]) * kx + lanesOf<V>(S[4]) * ky + lanesOf<V>(S[5]) * kz;
      const V skz = lanesOf<V>(S[6]) * kx + lanesOf<V>(S[7]) * ky + lanesOf<V>(S[8]) * kz;
      const V qex = qx + d * skx, qey = qy + d * sky, qez = qz + d * skz;
      const M end_in = (qex * qex + qey * qey + qez * qez) - 1.0 <= 1e-12;
      full = full | (reach & inside_now);
      // The segment and the end's path only for the lanes they can still flag: not already flagged (by this
      // body's end or an earlier body), with the pivot outside (a pivot inside takes the end's test alone).
      const M open = reach & ~end_in & ~hit & ~full & ~pivot_inside;
      hit = hit | (reach & end_in);
      if (anyLane(open)) {
        M path = pathEnters(qx, qy, qz, qex, qey, qez);
        if (have_before) path = path | pathEnters(bx1, by1, bz1, qex, qey, qez);
        hit = hit | (open & path);
      }
    }
    flag = flag | full | hit | bent;

    // The state at the end of the substep; the new ends are the next row's pivots.
    const V midx = px + hd * kx, midy = py + hd * ky, midz = pz + hd * kz;
    const V velx = (midx - mx) / dt, vely = (midy - my) / dt, velz = (midz - mz) / dt;
    const M code = (full & kPointFull) | (bent & ~full & kPointBend) | (hit & ~full & kPointBodies);
    storeVec3<N>(job.out_direction, pt, pairs, kx, ky, kz);
    storeVec3<N>(job.out_rate, pt, pairs, Wx, Wy, Wz);
    storeVec3<N>(job.out_position, pt, pairs, nex, ney, nez);
    storeVec3<N>(job.out_velocity, pt, pairs, velx, vely, velz);
    typedef typename VecTypes<N>::C C;
    const C code_bytes = __builtin_convertvector(code, C);
    if (pairs) {  // lanes 2m and 2m + 1 at consecutive points
      for (int l = 0; l < N; l += 2)
        __builtin_memcpy(job.out_flag + pt[l], reinterpret_cast<const unsigned char*>(&code_bytes) + l, 2);
    } else {
      for (int l = 0; l < N; ++l)
        if (pt[l] >= 0) job.out_flag[pt[l]] = code_bytes[l];
    }
    px = nex, py = ney, pz = nez;
    opx = ex, opy = ey, opz = ez;
    first_row = sel(flag & (first_row == 0), M{} + r, first_row);
  }
  for (int l = 0; l < N; ++l) {
    job.first_flagged_row[l0 + l] = static_cast<int>(first_row[l]);
    job.max_rate2[l0 + l] = max_rate2[l];
  }
}

void stepBlockBaseline(BlockJob& job) {
  for (int l0 = 0; l0 < W; l0 += 2)
    job.have_before ? blockBody<2, true>(job, l0) : blockBody<2, false>(job, l0);
}

#if defined(HAIR_SIM_AVX2_DISPATCH)
/// The block in 256-bit vectors (inlined into each target below).
HAIR_SIM_ALWAYS_INLINE void stepBlock4(BlockJob& job) {
  static_assert(W % 4 == 0, "blocks of whole AVX2 vectors");
  for (int l0 = 0; l0 < W; l0 += 4)
    job.have_before ? blockBody<4, true>(job, l0) : blockBody<4, false>(job, l0);
}
__attribute__((target("avx2"))) void stepBlockAvx2(BlockJob& job) { stepBlock4(job); }
/// The same compiled with AVX-512VL: the same 256-bit operations (no FMA contraction, so the same bits), with
/// 32 vector registers instead of 16, so fewer spills to the stack (the kernel's instructions 5,930 -> 5,106,
/// 2026-11-26).
__attribute__((target("avx2,avx512f,avx512vl"))) void stepBlockAvx512(BlockJob& job) { stepBlock4(job); }
#endif

}  // namespace

void fillLaneConstants(double* out, const int* point, int rows, const Vec3* rest_dir, const Vec3* styled_dir,
                       const double* length, const double* inv_inertia) {
  for (int r = 0; r < rows; ++r)
    for (int l = 0; l < W; ++l) {
      const int i = point[r * W + l];
      double* k = out + static_cast<std::ptrdiff_t>(r) * kConstants * W + l;
      const Vec3 u = i >= 0 ? rest_dir[i] : Vec3::UnitZ();
      const Vec3 s = i >= 0 ? styled_dir[i] : Vec3::UnitZ();
      const double v[kConstants] = {
          u.x(), u.y(), u.z(), s.x(), s.y(), s.z(), i >= 0 ? length[i] : 1.0, i >= 0 ? inv_inertia[i] : 0.0};
      for (int c = 0; c < kConstants; ++c) k[c * W] = v[c];
    }
}

BlockKernel blockKernel(Isa isa) {
#if defined(HAIR_SIM_AVX2_DISPATCH)
  if (isa == Isa::Best && cpuHasAvx512vl()) return stepBlockAvx512;
  if (isa != Isa::Baseline && cpuHasAvx2()) return stepBlockAvx2;
#endif
  (void)isa;
  return stepBlockBaseline;
}

const char* kernelName(Isa isa) {
#if defined(HAIR_SIM_AVX2_DISPATCH)
  const BlockKernel kernel = blockKernel(isa);
  if (kernel == stepBlockAvx512) return "AVX-512VL";
  if (kernel == stepBlockAvx2) return "AVX2";
#endif
  (void)isa;
#if defined(__x86_64__)
  return "x86-64";
#else
  return "baseline";  // the generic vector code, as the compiler targets this build
#endif
}

}  // namespace lanes
}  // namespace hair_sim
