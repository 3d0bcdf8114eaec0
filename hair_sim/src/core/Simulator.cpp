#include "hair_sim/core/Simulator.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "LaneWorkers.hpp"
#include "RotationSeries.hpp"
#include "StepLanes.hpp"
#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 anyPerpendicular(const Vec3& a) {
  const Vec3 helper = std::abs(a.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return a.cross(helper).normalized();
}

}  // namespace

Vec3 rotationVectorBetween(const Vec3& a, const Vec3& b) {
  const Vec3 axis = a.cross(b);
  const double c = a.dot(b);
  const double s2 = axis.squaredNorm();
  // Small angles (the hinges, a substep's turn): angle / s = atan(x) / (x c) with x = s / c < 0.1, the
  // series of atan(x) / x in x^2 to x^16 (the first term left out, x^18 / 19, is below 6e-20): no
  // square root and no atan2.
  if (c > 0.0 && s2 > 1e-24 && s2 < 0.01 * (c * c)) {
    const double x2 = s2 / (c * c);
    const double p = series::atanOverX(x2);
    return axis * (p / c);
  }
  const double s = std::sqrt(s2);
  const double angle = std::atan2(s, c);
  if (s > 1e-12) return axis * (angle / s);
  if (c > 0.0) return Vec3::Zero();
  return anyPerpendicular(a) * angle;
}

Vec3 rotateByVector(const Vec3& w, const Vec3& v) {
  const double a2 = w.squaredNorm();
  if (a2 < 1e-24) return v + w.cross(v);
  if (a2 < 0.01) {
    // Small angles (a substep's turn): v cos + (w x v) sin(a) / a + w (w.v) (1 - cos) / a^2 with the three
    // series in a^2 < 0.01 to a^10 (the terms left out are below 2e-21): no square root, no sin or cos,
    // and no cancellation in 1 - cos.
    double c, sa, ca;
    series::rotation(a2, c, sa, ca);
    return v * c + w.cross(v) * sa + w * (w.dot(v) * ca);
  }
  const double angle = std::sqrt(a2);
  const Vec3 k = w / angle;
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  return v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c));
}

Vec3 rotatePerpendicular(const Vec3& w, const Vec3& v) {
  const double a2 = w.squaredNorm();
  if (a2 < 1e-24) return v + w.cross(v);
  if (a2 >= 0.01) return rotateByVector(w, v);
  double c, sa;
  series::rotationCosSin(a2, c, sa);
  return v * c + w.cross(v) * sa;
}

Mat3 minimalRotation(const Vec3& a, const Vec3& b) {
  const double c = a.dot(b);
  if (c < -1.0 + 1e-9) {
    const Vec3 k = anyPerpendicular(a);
    return 2.0 * k * k.transpose() - Mat3::Identity();
  }
  // Rodrigues for unit a, b: I + [v]x + [v]x^2 / (1 + c) with v = a x b, c = a.b; as [v]x^2 = v v^T - |v|^2 I
  // and |v|^2 = 1 - c^2, that is c I + [v]x + v v^T / (1 + c) (no matrix product).
  const Vec3 v = a.cross(b);
  const Vec3 h = v / (1.0 + c);
  Mat3 r = v * h.transpose();
  r.diagonal().array() += c;
  r(0, 1) -= v.z();
  r(0, 2) += v.y();
  r(1, 0) += v.z();
  r(1, 2) -= v.x();
  r(2, 0) -= v.y();
  r(2, 1) += v.x();
  return r;
}

double Simulator::inertiaFloor(double stiffness, double damping, double dt) {
  return std::max(damping * dt, 2.0 * stiffness * dt * dt);
}

Simulator::Simulator(Hairstyle hairstyle, PhysicsParameters parameters, std::vector<Body> bodies)
    : hairstyle_(std::move(hairstyle)), params_(std::move(parameters)), bodies_(std::move(bodies)) {
  params_.validate();
  hairstyle_.validate("Simulator::Simulator(...) : hairstyle");
  buildChains();
  buildSprings();
  reset();
}

void Simulator::buildChains() {
  const int n = hairstyle_.controlPointCount();
  const std::size_t sn = static_cast<std::size_t>(n);
  positions_.assign(sn, Vec3::Zero());
  velocity_.assign(sn, Vec3::Zero());
  direction_.assign(sn, Vec3::UnitZ());
  rate_.assign(sn, Vec3::Zero());
  styled_dir_.assign(sn, Vec3::UnitZ());
  rest_dir_.assign(sn, Vec3::UnitZ());
  length_.assign(sn, 0.0);
  inv_inertia_.assign(sn, 0.0);
  strip_offset_.clear();
  spring_force_.assign(sn, Vec3::Zero());
  moved_in_step_.assign(sn, -1);
  strip_of_point_.assign(sn, 0);
  margins_.clear();
  margin_of_strip_.clear();
  for (const Strip& s : hairstyle_.strips) {
    std::size_t m = 0;
    while (m < margins_.size() && margins_[m] != s.thickness_margin) ++m;
    if (m == margins_.size()) margins_.push_back(s.thickness_margin);
    margin_of_strip_.push_back(static_cast<int>(m));
  }
  int offset = 0;
  std::size_t largest = 0;
  for (const Strip& s : hairstyle_.strips) {
    largest = std::max(largest, static_cast<std::size_t>(s.pointCount()));
    strip_offset_.push_back(offset);
    for (int p = 0; p < s.pointCount(); ++p)
      strip_of_point_[static_cast<std::size_t>(offset + p)] = static_cast<int>(strip_offset_.size() - 1);
    for (int r = 1; r < s.rows; ++r) {
      for (int c = 0; c < s.columns; ++c) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const Vec3 seg = s.point(r, c) - s.point(r - 1, c);
        const double d = seg.norm();
        length_[i] = d;
        styled_dir_[i] = seg / d;
      }
    }
    offset += s.pointCount();
  }
  for (SweepScratch& w : scratch_)
    w.exact_placed.reserve(largest);  // (stepStrip's push_back never reallocates)
  updateSegmentConstants();
  buildLanes();
}

void Simulator::buildLanes() {
  constexpr int W = lanes::kLanes;
  std::vector<std::pair<int, int>> chains;  // (strip, column)
  int max_rows = 0;
  for (std::size_t si = 0; si < hairstyle_.strips.size(); ++si) {
    const Strip& s = hairstyle_.strips[si];
    max_rows = std::max(max_rows, s.rows);
    for (int c = 0; c < s.columns; ++c) chains.emplace_back(static_cast<int>(si), c);
  }
  const std::size_t blocks = (chains.size() + W - 1) / W;
  lane_stride_rows_ = max_rows;
  block_rows_.assign(blocks, 0);
  block_margin_.assign(blocks, -1);
  lane_point_.assign(blocks * static_cast<std::size_t>(max_rows) * W, -1);
  for (std::size_t ch = 0; ch < chains.size(); ++ch) {
    const std::size_t blk = ch / W, l = ch % W;
    const std::size_t si = static_cast<std::size_t>(chains[ch].first);
    const Strip& s = hairstyle_.strips[si];
    const int c = chains[ch].second;
    block_rows_[blk] = std::max(block_rows_[blk], s.rows);
    // A block whose strips differ in margin sees different inflated bodies: it takes the exact step.
    const int m = margin_of_strip_[si];
    block_margin_[blk] = (l == 0 || block_margin_[blk] == m) ? m : -2;
    for (int r = 0; r < s.rows; ++r)
      lane_point_[(blk * static_cast<std::size_t>(max_rows) + static_cast<std::size_t>(r)) * W + l] =
          strip_offset_[si] + s.index(r, c);
  }
  for (int& m : block_margin_) m = std::max(m, -1);
  strip_last_block_.assign(hairstyle_.strips.size(), 0);
  for (std::size_t ch = 0; ch < chains.size(); ++ch)
    strip_last_block_[static_cast<std::size_t>(chains[ch].first)] = static_cast<int>(ch / W);
  block_flags_.assign(blocks * W, 0);
  chain_max_rate2_.assign(blocks * W, 0.0);
  strip_first_chain_.assign(hairstyle_.strips.size(), 0);
  for (std::size_t ch = chains.size(); ch-- > 0;)  // the strip's columns are consecutive chains
    strip_first_chain_[static_cast<std::size_t>(chains[ch].first)] = static_cast<int>(ch);
  fillLaneConstants();
  const std::size_t n = positions_.size();
  lane_flag_.assign(n, lanes::kPointFull);
  new_position_.assign(n, Vec3::Zero());
  new_direction_.assign(n, Vec3::UnitZ());
  new_rate_.assign(n, Vec3::Zero());
  new_velocity_.assign(n, Vec3::Zero());
  strip_committed_.assign(hairstyle_.strips.size(), -1);
}

namespace {
/// The instruction sets a Lanes path's kernel may use.
lanes::Isa laneIsa(Simulator::StepPath path) {
  return path == Simulator::StepPath::LanesBaseline ? lanes::Isa::Baseline
         : path == Simulator::StepPath::LanesAvx2   ? lanes::Isa::UpToAvx2
                                                    : lanes::Isa::Best;
}

/// Equation (11) for the spring pair (a, b) outside its dead band, at l2 = |pos[b] - pos[a]|^2 and r2 = l2 /
/// rest^2: x = the stretch beyond the band (lo and hi: the proximity and far factors), F = -k_s x along the
/// pair, added to a and taken from b (pulls a toward b when stretched, pushes them apart when compressed;
/// none for a pair of length 0).
inline void addSpringForce(int a, int b, double rest, const Vec3* pos, Vec3* force, double l2, double r2,
                           double ks, double lo, double hi) {
  const double length = std::sqrt(l2);
  const double x = r2 < lo * lo ? length - lo * rest : length - hi * rest;
  if (x == 0.0 || length < 1e-12) return;
  const Vec3 f = (ks * x / length) * (pos[b] - pos[a]);
  force[a] += f;
  force[b] -= f;
}

/// A spring pair at squared length l2 (r2 = l2 / rest^2) into the extremes (within a strip or between
/// strips; a NaN never enters them: std::min / std::max); whether it is outside its dead band [lo2, hi2].
inline bool scanSpringPair(SpringExtremes& e, bool within, double l2, double r2, double lo2, double hi2) {
  if (within) {
    e.min_within = std::min(e.min_within, r2);
    e.max_within = std::max(e.max_within, r2);
  } else {
    e.min_between = std::min(e.min_between, r2);
    e.max_between = std::max(e.max_between, r2);
    e.min_gap2 = std::min(e.min_gap2, l2);
  }
  return static_cast<bool>((r2 < lo2) | (r2 > hi2));
}
}  // namespace

double Simulator::bandDist2(const Vec3* pos, const BandPair& bp) {
  return (pos[static_cast<std::size_t>(bp.later)] - pos[static_cast<std::size_t>(bp.earlier)]).squaredNorm();
}

void Simulator::finishStripSprings(std::size_t si, const double* dist2, const Vec3* pos, SpringExtremes& e,
                                   int* outside) {
  const double ks = params_.spring_stiffness;
  const double lo = params_.spring_proximity_factor, hi = params_.spring_far_factor;
  std::fill_n(spring_force_.begin() + strip_offset_[si], hairstyle_.strips[si].pointCount(), Vec3::Zero());
  const int q0 = band_pair_start_[si], q1 = band_pair_start_[si + 1];
  int found = 0;
  for (int q = q0; q < q1; ++q) {  // the pairs outside listed without a branch (they come at random)
    const double l2 = dist2[q - q0];
    outside[found] = q;
    found += scanSpringPair(e, band_pairs_[static_cast<std::size_t>(q)].within, l2,
                            l2 * band_inv_rest2_[static_cast<std::size_t>(q)], lo * lo, hi * hi);
  }
  for (int n = 0; n < found; ++n) {
    const std::size_t q = static_cast<std::size_t>(outside[n]);
    const BandPair& bp = band_pairs_[q];
    const double l2 = dist2[outside[n] - q0];
    addSpringForce(bp.later_is_b ? bp.earlier : bp.later, bp.later_is_b ? bp.later : bp.earlier,
                   band_rest_[q], pos, spring_force_.data(), l2, l2 * band_inv_rest2_[q], ks, lo, hi);
  }
}

void Simulator::finishRootSprings(const Vec3* pos, SpringExtremes& e) {
  const double lo = params_.spring_proximity_factor, hi = params_.spring_far_factor;
  for (const int k : root_springs_) {
    const SpringPair& p = springs_[static_cast<std::size_t>(k)];
    const double l2 = (pos[p.b] - pos[p.a]).squaredNorm();
    const double r2 = l2 * spring_inv_rest2_[static_cast<std::size_t>(k)];
    if (scanSpringPair(e, p.within_strip, l2, r2, lo * lo, hi * hi))
      addSpringForce(p.a, p.b, p.rest, pos, spring_force_.data(), l2, r2, params_.spring_stiffness, lo, hi);
  }
}

const char* Simulator::kernelInstructionSet(StepPath path) {
  return path == StepPath::Exact ? "none" : lanes::kernelName(laneIsa(path));
}

void Simulator::stepLanes(const StepInputs& in, const StepFrame& f) {
  constexpr int W = lanes::kLanes;
  const std::size_t nb = bodies_.size();
  lane_bodies_.resize(margins_.size() * nb);
  for (std::size_t m = 0; m < margins_.size() && nb > 0; ++m)
    for (std::size_t b = 0; b < nb; ++b) {
      lanes::LaneBody& lb = lane_bodies_[m * nb + b];
      const Ellipsoid& now = bodies_now_[m][b];
      const Ellipsoid& before = have_bodies_before_ ? bodies_before_[m][b] : now;
      const BodyBound& bound = body_bounds_[m][b];
      for (int l = 0; l < lanes::LaneBody::kCopies; ++l) {
        for (int r = 0; r < 3; ++r) {
          lb.centre[r][l] = now.center()[r];
          lb.centre_before[r][l] = before.center()[r];
          for (int c = 0; c < 3; ++c) {
            lb.sinv[3 * r + c][l] = now.Sinv()(r, c);
            lb.sinv_before[3 * r + c][l] = before.Sinv()(r, c);
          }
        }
        lb.bound_radius[l] = bound.radius;
        lb.shift[l] = bound.shift;
        lb.grow[l] = 1.0 + bound.motion;
        lb.keep2[l] = (1.0 - bound.motion) * (1.0 - bound.motion);
        lb.slow[l] = bound.motion < 0.5 ? -1 : 0;
      }
    }

  // The next substep's springs (computeSpringForces), strip by strip as the sweeps find their pairs' final
  // lengths (finishStripSprings): the extremes of the lengths, in each sweep's scratch, and (11) for the
  // pairs outside their dead band, added to spring_force_ in place. A strip's forces are cleared once its
  // sweep no longer reads them (after its exact step), before any pair with it is final: a pair is final when
  // the later of its strips in the sweep order is swept, and the kernel reads a strip's forces before that
  // (its blocks are computed first). So every point's force is summed in the sweep order, as
  // computeSpringForces sums it when it computes them itself. A point's pairs lie in its own group, or join
  // it to the boundary (added in the boundary's sweep, after both groups), or have a root (added after every
  // sweep): on 2 threads the two groups' sweeps never add to the same point, and their interleaving changes
  // no point's order.
  for (SweepScratch& w : scratch_) w.extremes = SpringExtremes();
  lanes::BlockJob job;
  job.dt = f.dt, job.k = f.k, job.gamma = f.gamma, job.drag = f.drag;
  job.max_angle_step = params_.max_angle_step;
  job.cos_max_bend = f.cos_max_bend;
  for (int r = 0; r < 3; ++r) {
    job.force0[r] = f.force0[r];
    for (int c = 0; c < 3; ++c) {
      job.force_mid[3 * r + c] = f.force_mid(r, c);
      job.force_vel[3 * r + c] = f.force_vel(r, c);
    }
  }
  job.positions = positions_.data();
  job.direction = direction_.data();
  job.velocity = velocity_.data();
  job.rate = rate_.data();
  job.spring_force = spring_force_.data();
  job.out_position = new_position_.data();
  job.out_direction = new_direction_.data();
  job.out_rate = new_rate_.data();
  job.out_velocity = new_velocity_.data();
  job.out_flag = lane_flag_.data();
  job.body_count = static_cast<int>(nb);
  job.have_before = have_bodies_before_;
  job.turbulence = f.turbulent ? in.turbulence : nullptr;
  job.head_pose = &in.head.pose;
  job.head_rotation_inverse = &f.Rt;
  const lanes::BlockKernel kernel = lanes::blockKernel(laneIsa(step_path_));
  const std::size_t stride = static_cast<std::size_t>(lane_stride_rows_) * W;
  const std::size_t blocks = block_rows_.size();
  // Each sweep's thread its own copy of the job, of which runBlock sets the block's part (a copy per block
  // took 1 % of the step at 10,000 strips).
  std::array<lanes::BlockJob, 2> jobs{job, job};
  auto jobOf = [&](const SweepScratch& w) -> lanes::BlockJob& { return jobs[&w == &scratch_[1] ? 1 : 0]; };
  // One block of chains: reads only its own chains' state at the start of the substep, writes only their
  // new state and its flags (on any thread). Its chains' spring forces are still the substep's own as it is
  // computed before any of its strips is swept (the sweeps then write the next substep's in place).
  auto runBlock = [&](lanes::BlockJob& j, std::size_t blk) {
    if (block_margin_[blk] < 0) return;  // lane_flag_ keeps kPointFull there (buildLanes)
    j.rows = block_rows_[blk];
    j.point = &lane_point_[blk * stride];
    j.constants = &lane_constants_[blk * stride * lanes::kConstants];
    j.bodies = nb > 0 ? &lane_bodies_[static_cast<std::size_t>(block_margin_[blk]) * nb] : nullptr;
    kernel(j);
    std::copy(j.first_flagged_row, j.first_flagged_row + W, &block_flags_[blk * W]);
    std::copy(j.max_rate2, j.max_rate2 + W, &chain_max_rate2_[blk * W]);
  };
  // Helpers only for hairstyles of kMinBlocksForHelpers blocks or more: below, waking one costs more than it
  // saves (BM_Step2Threads/100: 0.5-1.1 x).
  LaneWorkers* workers = blocks >= kMinBlocksForHelpers ? workers_.get() : nullptr;
  // One group of the sweep order (buildSweepOrder) on one thread: its strips in that order, each once the
  // blocks through its last one are computed. The group's blocks [block_begin, block_end) are computed in
  // runs of kBlocksPerRun, each just before its strips are read: the kernel's code stays warm through a run,
  // and the run's results are still in the cache for the band check and the exact step. (On 2 threads the
  // other group's sweep computes some of them from the back as it goes, as many as LaneWorkers::Balance
  // says, and once done the rest not yet claimed: which thread computes a run does not change the bits.)
  // A strip is committed from the lanes when the spring band holds at its new places (what
  // resolveCollisions and the sweep's band check would act on) for its pairs within the strip and with the
  // strips before it in the sweep order, already final (with 1e-9 relative to spare; pairs with a root are
  // never moved, so never kept); otherwise it takes the exact step, which, like the lanes, sees the strips
  // after it as not yet moved. So both paths take the same decisions. The two groups share no spring pair
  // and no block, so they may be swept at once; the boundary (g = 2, no blocks of its own) comes after both.
  auto runOfBlocks = [&](lanes::BlockJob& j, std::size_t block_begin, std::size_t block_end,
                         std::size_t run) {
    const std::size_t end = std::min(block_end, block_begin + (run + 1) * kBlocksPerRun);
    for (std::size_t blk = block_begin + run * kBlocksPerRun; blk < end; ++blk) runBlock(j, blk);
  };
  const std::size_t mid = sweep_mid_block_;
  // Run `run` of group g (its blocks [0, mid) or [mid, blocks)), claimed from the helpers' claims by this
  // thread: computed and marked done for the other sweep.
  auto computeClaimedRun = [&](lanes::BlockJob& j, int g, std::size_t run) {
    runOfBlocks(j, g == 0 ? 0 : mid, g == 0 ? mid : blocks, run);
    workers->markRunDone(g, run);
  };
  const std::size_t runs0 = (mid + kBlocksPerRun - 1) / kBlocksPerRun;
  const std::size_t runs1 = (blocks - mid + kBlocksPerRun - 1) / kBlocksPerRun;
  struct Lending {
    int quota = 0;  // runs of the other group to compute
    int lent = 0;
    double seconds = 0.0;
    std::chrono::steady_clock::time_point end;  // of the sweep's own strips and the runs it lent
  } lendings[2];
  auto sweepGroup = [&](SweepScratch& w, int g, std::size_t order_begin, std::size_t order_end,
                        std::size_t block_begin, std::size_t block_end) {
    const std::size_t runs = (block_end - block_begin + kBlocksPerRun - 1) / kBlocksPerRun;
    std::size_t ready = 0;  // runs [0, ready) of the group are computed
    auto computeThrough = [&](std::size_t run) {
      for (; ready <= run && ready < runs; ++ready) {
        std::size_t claimed = ready;
        if (!workers || g == 2) {
          runOfBlocks(jobOf(w), block_begin, block_end, ready);
        } else if (workers->claimRun(g, false, claimed)) {  // (the front: the next run, ready)
          computeClaimedRun(jobOf(w), g, claimed);
        } else {
          workers->waitRunDone(g, ready);  // the other sweep claimed it from the back
        }
      }
    };
    double max_rate2 = 0.0;
    // On 2 threads, the runs of the other group this sweep computes as it goes (LaneWorkers::Balance),
    // spread over its strips, from the other group's back.
    Lending& lending = lendings[g < 2 ? g : 0];
    const std::size_t count = order_end - order_begin;
    for (std::size_t rank = order_begin; rank < order_end; ++rank) {
      const std::size_t si = static_cast<std::size_t>(sweep_order_[rank]);
      if (g < 2 && lending.quota > 0) {
        const std::size_t due = static_cast<std::size_t>(lending.quota) * (rank - order_begin + 1) / count;
        std::size_t run;
        while (static_cast<std::size_t>(lending.lent) < due && workers->claimRun(1 - g, true, run)) {
          const auto t0 = std::chrono::steady_clock::now();
          computeClaimedRun(jobOf(w), 1 - g, run);
          lending.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          ++lending.lent;
        }
      }
      if (runs > 0)
        computeThrough((static_cast<std::size_t>(strip_last_block_[si]) - block_begin) / kBlocksPerRun);
      const Strip& s = hairstyle_.strips[si];
      const int base = strip_offset_[si];
      // The exact step takes over at the first flagged place of the strip in its sweep (column by column,
      // root to tip): the places before it are the lanes'. A block of mixed margins is all exact.
      int from = kNoExact;
      const std::size_t chain0 = static_cast<std::size_t>(strip_first_chain_[si]);
      for (int c = 0; c < s.columns; ++c) {
        const std::size_t ch = chain0 + static_cast<std::size_t>(c);
        if (block_margin_[ch / W] < 0) {
          from = 0;
          break;
        }
        const int flagged = block_flags_[ch];
        if (flagged) from = std::min(from, c * s.rows + flagged);
      }
      // The band pairs' |a - b|^2 in the lanes' buffers (an earlier strip's final place is there: its lanes'
      // result, or its exact step's, copied there below), kept in w.band_dist2 for the spring scan.
      const int q0 = band_pair_start_[si], q1 = band_pair_start_[si + 1];
      double* band_dist2 = w.band_dist2.data();  // [q - q0]
      for (int q = q0; q < q1; ++q) {
        const BandPair& bp = band_pairs_[static_cast<std::size_t>(q)];
        const double dist2 = bandDist2(new_position_.data(), bp);
        band_dist2[q - q0] = dist2;
        // Kept by the later point of the pair in the sweep; without a branch (the pairs outside come at
        // random).
        const bool outside = (dist2 < bp.near2) | (dist2 > bp.far2);
        from = std::min(from, outside ? bp.key : kNoExact);
      }
      if (from != kNoExact) {
        stepStrip(w, in, f, si, base, w.tally, from, true);
        ++w.exact_strips;
        // Its state at the end of the substep into the lanes' buffers, which become the state below (its
        // blocks are computed): the points the exact step placed, or the whole strip after relaxStrip. The
        // points committed from the lanes are there already, and so are the roots, which no substep writes
        // (syncLaneBuffers made them equal in both).
        const auto copyBack = [this](std::size_t i) {
          new_position_[i] = positions_[i];
          new_direction_[i] = direction_[i];
          new_rate_[i] = rate_[i];
          new_velocity_[i] = velocity_[i];
        };
        if (w.exact_relaxed) {
          for (int p = 0; p < s.pointCount(); ++p) copyBack(static_cast<std::size_t>(base + p));
        } else {
          for (int i : w.exact_placed) copyBack(static_cast<std::size_t>(i));
        }
        for (int q = q0; q < q1; ++q)  // its pairs' final lengths
          band_dist2[q - q0] = bandDist2(new_position_.data(), band_pairs_[static_cast<std::size_t>(q)]);
        finishStripSprings(si, band_dist2, new_position_.data(), w.extremes, w.band_outside.data());
        continue;
      }
      // Committed: the lanes' buffers hold its state at the end of the substep (made the state below).
      strip_committed_[si] = sweep_;
      finishStripSprings(si, band_dist2, new_position_.data(), w.extremes, w.band_outside.data());
      for (int c = 0; c < s.columns; ++c)
        max_rate2 = std::max(max_rate2, chain_max_rate2_[chain0 + static_cast<std::size_t>(c)]);
    }
    if (runs > 0) computeThrough(runs - 1);  // the runs of boundary strips alone
    if (g < 2) lending.end = std::chrono::steady_clock::now();
    w.tally.max_rate2 = std::max(w.tally.max_rate2, max_rate2);
  };
  const std::size_t end0 = sweep_group_end_[0], end1 = sweep_group_end_[1], end2 = sweep_group_end_[2];
  if (workers) {
    // The second group on a helper (or here, if none has taken it by the time the first is done); each sweep,
    // once done, computes the other group's unclaimed runs.
    struct SecondGroup {
      decltype(sweepGroup)* sweep;
      decltype(computeClaimedRun)* compute;
      lanes::BlockJob* job;
      LaneWorkers* workers;
      SweepScratch* w;
      std::size_t order_begin, order_end, mid, blocks;
      std::exception_ptr error;
    } second{&sweepGroup, &computeClaimedRun, &jobs[1], workers, &scratch_[1], end0, end1, mid, blocks,
             nullptr};
    // The helper holds references into this frame: it is done before it ends, whatever happens.
    struct FinishHelpers {
      LaneWorkers* workers;
      ~FinishHelpers() { workers->finish(); }
    } finish_helpers{workers};
    workers->startRuns(runs0, runs1);
    const int lend = workers->balance.lend;
    lendings[0].quota = std::max(lend, 0);
    lendings[1].quota = std::max(-lend, 0);
    const auto start = std::chrono::steady_clock::now();
    workers->start(
        1,
        [](void* context, std::size_t) {
          SecondGroup& g = *static_cast<SecondGroup*>(context);
          try {
            (*g.sweep)(*g.w, 1, g.order_begin, g.order_end, g.mid, g.blocks);
            std::size_t run;
            while (g.workers->claimRun(0, true, run)) (*g.compute)(*g.job, 0, run);
          } catch (...) {
            g.error = std::current_exception();
          }
        },
        &second);
    sweepGroup(scratch_[0], 0, 0, end0, 0, mid);
    std::size_t run;
    while (workers->claimRun(1, true, run)) computeClaimedRun(jobs[0], 1, run);
    workers->waitFor(0);
    if (second.error) std::rethrow_exception(second.error);
    auto since = [&](const Lending& l) { return std::chrono::duration<double>(l.end - start).count(); };
    workers->settle(since(lendings[0]), since(lendings[1]), lendings[0].seconds + lendings[1].seconds,
                    lendings[0].lent + lendings[1].lent, static_cast<int>(runs0), static_cast<int>(runs1));
  } else {
    sweepGroup(scratch_[0], 0, 0, end0, 0, mid);
    sweepGroup(scratch_[1], 1, end0, end1, mid, blocks);
  }
  sweepGroup(scratch_[0], 2, end1, end2, blocks, blocks);  // the boundary, after both
  // The lanes' buffers hold every strip's state at the end of the substep: they become the state (no copy of
  // the strips committed from the lanes).
  positions_.swap(new_position_);
  direction_.swap(new_direction_);
  rate_.swap(new_rate_);
  velocity_.swap(new_velocity_);
  // The pairs with a root (no band pair) at the state's places: the scan is then whole.
  finishRootSprings(positions_.data(), scratch_[0].extremes);
  spring_scan_sweep_ = sweep_;
}

void Simulator::syncLaneBuffers() {
  new_position_ = positions_;
  new_direction_ = direction_;
  new_rate_ = rate_;
  new_velocity_ = velocity_;
}

Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

void Simulator::setThreads(int threads) {
  if (threads < 1 || threads > 64)
    throw std::invalid_argument("Simulator::setThreads(...) : threads must be in [1, 64], got " +
                                std::to_string(threads));
  if (threads == this->threads()) return;
  workers_.reset();
  if (threads > 1) workers_ = std::make_unique<LaneWorkers>(threads - 1);
}

int Simulator::threads() const { return workers_ ? workers_->helpers() + 1 : 1; }

double Simulator::commitLanes(std::size_t i) {
  positions_[i] = new_position_[i];
  direction_[i] = new_direction_[i];
  rate_[i] = new_rate_[i];
  velocity_[i] = new_velocity_[i];
  moved_in_step_[i] = sweep_;
  return rate_[i].squaredNorm();
}

void Simulator::fillLaneConstants() {
  const std::size_t stride = static_cast<std::size_t>(lane_stride_rows_) * lanes::kLanes;
  const std::size_t blocks = block_rows_.size();
  lane_constants_.assign(blocks * stride * lanes::kConstants, 0.0);
  for (std::size_t blk = 0; blk < blocks; ++blk)
    lanes::fillLaneConstants(&lane_constants_[blk * stride * lanes::kConstants], &lane_point_[blk * stride],
                             lane_stride_rows_, rest_dir_.data(), styled_dir_.data(), length_.data(),
                             inv_inertia_.data());
}

void Simulator::updateSegmentConstants() {
  const double dt = params_.substep;
  const double k = params_.hinge_stiffness;
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int r = 1; r < s.rows; ++r) {
      for (int c = 0; c < s.columns; ++c) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const double d = length_[i];
        const double inertia = params_.linear_density * d * d * d / 3.0;
        // Linear springs at the lever d/2: the collision constraint and up to the springs of this point.
        const int pairs = (params_.springs_within_strips ? 2 : 0) +
                          (params_.springs_between_strips ? params_.spring_max_pairs : 0);
        const double k_lin = params_.collision_stiffness + pairs * params_.spring_stiffness;
        const double c_lin = params_.collision_damping + params_.air_drag * d;
        const double floor =
            inertiaFloor(k + k_lin * 0.25 * d * d, params_.hinge_damping + c_lin * 0.25 * d * d, dt);
        inv_inertia_[i] = 1.0 / std::max(inertia, floor);
        // Compensation: the hinge is pre-bent so that at the styled direction its torque cancels the
        // torque of gravity: rest = exp(-tau_g / k) styled, tau_g = (d/2) n x (rho d g).
        Vec3 rest = styled_dir_[i];
        if (params_.compensate_rest_angles && k > 0.0) {
          const Vec3 tau_g = 0.5 * d * styled_dir_[i].cross(params_.linear_density * d * params_.gravity);
          rest = rotateByVector(-tau_g / k, styled_dir_[i]);
        }
        rest_dir_[i] = rest;
      }
    }
    offset += s.pointCount();
  }
}

void Simulator::setParameters(const PhysicsParameters& parameters) {
  parameters.validate();
  if (parameters.substep != params_.substep)
    throw std::invalid_argument("Simulator::setParameters(...) : substep " +
                                std::to_string(parameters.substep) + " differs from the running " +
                                std::to_string(params_.substep) + " s: build a new Simulator to change it");
  const bool pairing_changed = parameters.springs_within_strips != params_.springs_within_strips ||
                               parameters.springs_between_strips != params_.springs_between_strips ||
                               parameters.spring_radius != params_.spring_radius ||
                               parameters.spring_max_pairs != params_.spring_max_pairs;
  params_ = parameters;
  updateSegmentConstants();
  fillLaneConstants();
  if (pairing_changed)
    buildSprings();
  else
    buildBandPairs();  // the band's factors may have changed
}

void Simulator::reset() {
  spring_scan_sweep_ = -1;  // (the hair moves: the next scan reads the points)
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int p = 0; p < s.pointCount(); ++p)
      positions_[static_cast<std::size_t>(offset + p)] = s.points[static_cast<std::size_t>(p)];
    offset += s.pointCount();
  }
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    direction_[i] = styled_dir_[i];
    rate_[i].setZero();
    velocity_[i].setZero();
  }
  steps_ = 0;
  max_rate_ = 0.0;
  have_bodies_before_ = false;
  max_penetration_ = 0.0;
  penetrations_ = 0;
  collisions_ = 0;
  // The roots, which no substep writes, the same in the lanes' buffers (stepLanes swaps them with the state).
  syncLaneBuffers();
}

void Simulator::buildSprings() {
  springs_.clear();
  // The last substep's forces and measures go with the pairs (without springs step() computes none to
  // replace them): no force, and the ratios and gap of a Simulator without springs.
  std::fill(spring_force_.begin(), spring_force_.end(), Vec3::Zero());
  min_ratio_[0] = min_ratio_[1] = max_ratio_[0] = max_ratio_[1] = 1.0;
  min_gap_ = 0.0;
  std::vector<Vec3> styled;  // pairs and rest lengths come from the styled shape
  for (const Strip& s : hairstyle_.strips) styled.insert(styled.end(), s.points.begin(), s.points.end());
  if (params_.springs_within_strips) {
    for (std::size_t si = 0; si < hairstyle_.strips.size(); ++si) {
      const Strip& s = hairstyle_.strips[si];
      for (int r = 1; r < s.rows; ++r)
        for (int c = 0; c + 1 < s.columns; ++c) {
          SpringPair pair;
          pair.a = strip_offset_[si] + s.index(r, c);
          pair.b = strip_offset_[si] + s.index(r, c + 1);
          pair.rest =
              (styled[static_cast<std::size_t>(pair.a)] - styled[static_cast<std::size_t>(pair.b)]).norm();
          pair.within_strip = true;
          if (pair.rest > 1e-6) springs_.push_back(pair);
        }
    }
  }
  const double radius = params_.spring_radius;
  if (params_.springs_between_strips && radius > 0.0 && params_.spring_max_pairs > 0) {
    // k nearest partners through a uniform grid stored densely (counting sort into cells, CSR). The
    // cell is radius / m, with m chosen from the mean occupancy of radius-sized cells so that a cell
    // holds a few points whatever the density; each point scans shells of cells outward and stops
    // once the k-th nearest is closer than the shell. Set-up is linear in the number of strips.
    std::vector<int> movable;
    movable.reserve(styled.size());
    std::vector<char> is_root(styled.size(), 0);
    for (std::size_t si = 0; si < hairstyle_.strips.size(); ++si)
      for (int c = 0; c < hairstyle_.strips[si].columns; ++c)
        is_root[static_cast<std::size_t>(strip_offset_[si] + c)] = 1;
    Eigen::AlignedBox3d box;
    for (std::size_t i = 0; i < styled.size(); ++i)
      if (!is_root[i]) {
        movable.push_back(static_cast<int>(i));
        box.extend(styled[i]);
      }
    if (!movable.empty()) {
      // Occupancy of radius-sized cells that hold points: a surface-like layer of hair, so the
      // subdivision m grows with the square root of the occupancy.
      std::unordered_set<std::int64_t> used;
      for (int i : movable) {
        const Vec3 q = (styled[static_cast<std::size_t>(i)] - box.min()) / radius;
        used.insert((static_cast<std::int64_t>(q.x()) << 42) | (static_cast<std::int64_t>(q.y()) << 21) |
                    static_cast<std::int64_t>(q.z()));
      }
      const double occupancy = static_cast<double>(movable.size()) / static_cast<double>(used.size());
      int m = std::max(1, std::min(16, static_cast<int>(std::ceil(std::sqrt(occupancy / 4.0)))));
      const Vec3 extent = box.max() - box.min();
      Eigen::Vector3i dims;
      double cell = radius / m;
      for (;;) {
        for (int a = 0; a < 3; ++a) dims[a] = static_cast<int>(std::floor(extent[a] / cell)) + 1;
        if (static_cast<double>(dims.x()) * dims.y() * dims.z() <= 8e6 || m == 1) break;
        --m;  // keep the dense grid within a few tens of MB
        cell = radius / m;
      }
      auto cellOf = [&](const Vec3& p) {
        Eigen::Vector3i c;
        for (int a = 0; a < 3; ++a)
          c[a] =
              std::min(dims[a] - 1, std::max(0, static_cast<int>(std::floor((p[a] - box.min()[a]) / cell))));
        return c;
      };
      auto flat = [&](const Eigen::Vector3i& c) {
        return (static_cast<std::size_t>(c.z()) * static_cast<std::size_t>(dims.y()) +
                static_cast<std::size_t>(c.y())) *
                   static_cast<std::size_t>(dims.x()) +
               static_cast<std::size_t>(c.x());
      };
      const std::size_t cells = static_cast<std::size_t>(dims.x()) * static_cast<std::size_t>(dims.y()) *
                                static_cast<std::size_t>(dims.z());
      std::vector<int> cell_start(cells + 1, 0);
      for (int i : movable) ++cell_start[flat(cellOf(styled[static_cast<std::size_t>(i)])) + 1];
      for (std::size_t c = 0; c < cells; ++c) cell_start[c + 1] += cell_start[c];
      std::vector<int> cell_points(movable.size());
      {
        std::vector<int> fill(cell_start.begin(), cell_start.end() - 1);
        for (int i : movable)
          cell_points[static_cast<std::size_t>(fill[flat(cellOf(styled[static_cast<std::size_t>(i)]))]++)] =
              i;
      }
      const std::size_t k = static_cast<std::size_t>(params_.spring_max_pairs);
      std::vector<std::pair<double, int>> near;
      std::unordered_set<std::int64_t> paired;
      for (int ii : movable) {
        const std::size_t i = static_cast<std::size_t>(ii);
        near.clear();
        const Eigen::Vector3i c = cellOf(styled[i]);
        for (int ring = 0; ring <= m; ++ring) {
          for (int dz = -ring; dz <= ring; ++dz) {
            const int z = c.z() + dz;
            if (z < 0 || z >= dims.z()) continue;
            for (int dy = -ring; dy <= ring; ++dy) {
              const int y = c.y() + dy;
              if (y < 0 || y >= dims.y()) continue;
              const bool face = std::abs(dz) == ring || std::abs(dy) == ring;
              for (int dx = -ring; dx <= ring; dx += (face || ring == 0) ? 1 : 2 * ring) {  // the shell only
                const int x = c.x() + dx;
                if (x < 0 || x >= dims.x()) continue;
                const std::size_t f = flat(Eigen::Vector3i(x, y, z));
                for (int q = cell_start[f]; q < cell_start[f + 1]; ++q) {
                  const int j = cell_points[static_cast<std::size_t>(q)];
                  if (strip_of_point_[static_cast<std::size_t>(j)] == strip_of_point_[i]) continue;
                  const double dist = (styled[static_cast<std::size_t>(j)] - styled[i]).norm();
                  if (dist < radius && dist > 1e-6) near.push_back({dist, j});
                }
              }
            }
          }
          // Every point closer than ring * cell has been seen: stop when the k nearest are all that close.
          if (near.size() >= k) {
            std::nth_element(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k - 1), near.end());
            if (near[k - 1].first <= ring * cell) break;
          }
        }
        const std::size_t keep = std::min(near.size(), k);
        std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(keep), near.end());
        for (std::size_t n = 0; n < keep; ++n) {
          const int j = near[n].second;
          const int a = std::min(j, ii), b = std::max(j, ii);
          if (!paired.insert((static_cast<std::int64_t>(a) << 32) | b).second) continue;  // each pair once
          springs_.push_back(SpringPair{ii, j, near[n].first, false});
        }
      }
    }
  }
  // Partners of each point (both directions) for the hard band in resolveCollisions.
  const std::size_t n = positions_.size();
  partner_start_.assign(n + 1, 0);
  for (const SpringPair& p : springs_) {
    ++partner_start_[static_cast<std::size_t>(p.a) + 1];
    ++partner_start_[static_cast<std::size_t>(p.b) + 1];
  }
  for (std::size_t k = 0; k < n; ++k) partner_start_[k + 1] += partner_start_[k];
  spring_inv_rest2_.resize(springs_.size());
  for (std::size_t k = 0; k < springs_.size(); ++k)
    spring_inv_rest2_[k] = 1.0 / (springs_[k].rest * springs_[k].rest);
  partner_index_.assign(static_cast<std::size_t>(partner_start_[n]), 0);
  partner_rest_.assign(static_cast<std::size_t>(partner_start_[n]), 0.0);
  partner_strip_.assign(static_cast<std::size_t>(partner_start_[n]), 0);
  std::vector<int> fill(partner_start_.begin(), partner_start_.end() - 1);
  for (const SpringPair& p : springs_) {
    const std::size_t fa = static_cast<std::size_t>(fill[static_cast<std::size_t>(p.a)]++);
    partner_index_[fa] = p.b;
    partner_rest_[fa] = p.within_strip ? p.rest : -p.rest;  // negative: between strips
    const std::size_t fb = static_cast<std::size_t>(fill[static_cast<std::size_t>(p.b)]++);
    partner_index_[fb] = p.a;
    partner_rest_[fb] = p.within_strip ? p.rest : -p.rest;
  }
  for (std::size_t q = 0; q < partner_index_.size(); ++q)
    partner_strip_[q] = strip_of_point_[static_cast<std::size_t>(partner_index_[q])];
  buildBandPairs();
}

void Simulator::buildSweepOrder() {
  constexpr int W = lanes::kLanes;
  const std::size_t n = hairstyle_.strips.size();
  const std::size_t blocks = block_rows_.size();
  sweep_mid_block_ = blocks / 2;
  // Per strip: 0 with all its chains in the blocks before the middle one, 1 from it on, 2 both (boundary).
  std::vector<char> group(n, 2);
  for (std::size_t si = 0; si < n; ++si) {
    const std::size_t first = static_cast<std::size_t>(strip_first_chain_[si]) / W;
    const std::size_t last = static_cast<std::size_t>(strip_last_block_[si]);
    group[si] = last < sweep_mid_block_ ? 0 : first >= sweep_mid_block_ ? 1 : 2;
  }
  // A pair between the halves puts both its strips in the boundary (a pair with a boundary strip does not:
  // that strip comes after both groups).
  std::vector<char> boundary(n, 0);
  for (const SpringPair& p : springs_) {
    const std::size_t a = static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(p.a)]);
    const std::size_t b = static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(p.b)]);
    if (group[a] != 2 && group[b] != 2 && group[a] != group[b]) boundary[a] = boundary[b] = 1;
  }
  for (std::size_t si = 0; si < n; ++si)
    if (boundary[si]) group[si] = 2;
  sweep_order_.clear();
  for (char g = 0; g < 3; ++g) {
    for (std::size_t si = 0; si < n; ++si)
      if (group[si] == g) sweep_order_.push_back(static_cast<int>(si));
    sweep_group_end_[static_cast<std::size_t>(g)] = sweep_order_.size();
  }
  strip_rank_.assign(n, 0);
  for (std::size_t r = 0; r < n; ++r)
    strip_rank_[static_cast<std::size_t>(sweep_order_[r])] = static_cast<int>(r);
  partner_rank_.resize(partner_strip_.size());
  for (std::size_t q = 0; q < partner_strip_.size(); ++q)
    partner_rank_[q] = strip_rank_[static_cast<std::size_t>(partner_strip_[q])];
}

void Simulator::buildBandPairs() {
  buildSweepOrder();
  // Per strip, the spring pairs whose later point in the sweep is in it, neither point a root (roots never
  // move, so the exact step never keeps such a pair), with the squared edges of the hard band (the contact
  // edge and the far edge; 1e-9 relative to spare).
  const double lo = contactFactor(), hi = params_.spring_far_factor;
  band_pairs_.clear();
  band_pair_start_.assign(hairstyle_.strips.size() + 1, 0);
  auto isRoot = [&](int k) {
    const std::size_t t = static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(k)]);
    return k - strip_offset_[t] < hairstyle_.strips[t].columns;
  };
  std::vector<BandPair> pairs;
  std::vector<int> pair_springs;  // of pairs
  root_springs_.clear();
  spring_scan_sweep_ = -1;
  for (std::size_t k = 0; k < springs_.size(); ++k) {
    const SpringPair& p = springs_[k];
    if (isRoot(p.a) || isRoot(p.b)) {
      root_springs_.push_back(static_cast<int>(k));
      continue;
    }
    BandPair bp;
    // The later point: of the strip later in the sweep order, or within one strip the later in its numbering
    // (the sweep keys below decide the place where the pair is kept).
    const int rank_a = strip_rank_[static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(p.a)])];
    const int rank_b = strip_rank_[static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(p.b)])];
    const bool a_later = rank_a != rank_b ? rank_a > rank_b : p.a > p.b;
    bp.later = a_later ? p.a : p.b;
    bp.earlier = a_later ? p.b : p.a;
    bp.later_is_b = !a_later;
    bp.within = p.within_strip;
    bp.near2 = (lo * p.rest) * (lo * p.rest) * (1.0 + 1e-9);
    bp.far2 = p.within_strip ? (hi * p.rest) * (hi * p.rest) * (1.0 - 1e-9)
                             : std::numeric_limits<double>::infinity();
    const std::size_t t = static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(bp.later)]);
    const Strip& s = hairstyle_.strips[t];
    auto sweepKey = [&](int point) {  // place of a point of strip t in its sweep
      const int local = point - strip_offset_[t];
      return (local % s.columns) * s.rows + local / s.columns;
    };
    const bool same_strip = strip_of_point_[static_cast<std::size_t>(bp.earlier)] == static_cast<int>(t);
    bp.key = same_strip ? std::max(sweepKey(bp.later), sweepKey(bp.earlier)) : sweepKey(bp.later);
    pairs.push_back(bp);
    pair_springs.push_back(static_cast<int>(k));
    ++band_pair_start_[t + 1];
  }
  max_band_pairs_ = 0;
  for (std::size_t t = 0; t < hairstyle_.strips.size(); ++t) {
    max_band_pairs_ = std::max(max_band_pairs_, static_cast<std::size_t>(band_pair_start_[t + 1]));
    band_pair_start_[t + 1] += band_pair_start_[t];
  }
  for (SweepScratch& w : scratch_) {  // a strip's band pairs at a time (stepLanes, computeSpringForces)
    w.band_dist2.resize(max_band_pairs_);
    w.band_outside.resize(max_band_pairs_);
  }
  band_pairs_.resize(pairs.size());
  band_inv_rest2_.resize(pairs.size());
  band_rest_.resize(pairs.size());
  std::vector<int> fill(band_pair_start_.begin(), band_pair_start_.end() - 1);
  for (std::size_t n = 0; n < pairs.size(); ++n) {
    const BandPair& bp = pairs[n];
    const std::size_t q = static_cast<std::size_t>(
        fill[static_cast<std::size_t>(strip_of_point_[static_cast<std::size_t>(bp.later)])]++);
    const std::size_t k = static_cast<std::size_t>(pair_springs[n]);
    band_pairs_[q] = bp;
    band_inv_rest2_[q] = spring_inv_rest2_[k];
    band_rest_[q] = springs_[k].rest;
  }
}

void Simulator::computeSpringForces() {
  // (11) for the pairs outside their dead band (most pairs are within it: no square root, no division) and
  // the extremes of the pairs' lengths. When the last substep took the lanes and nothing has moved the hair
  // since, stepLanes' sweeps did both as they found each pair's final length: the forces are in
  // spring_force_ and the extremes in the sweeps' scratch. Else here from the points, strip by strip in the
  // sweep order as the sweeps do it (finishStripSprings, then finishRootSprings): every point's force summed
  // in the same order, so the same bits.
  SpringExtremes e;
  auto merge = [&e](const SpringExtremes& from) {
    e.min_within = std::min(e.min_within, from.min_within);
    e.max_within = std::max(e.max_within, from.max_within);
    e.min_between = std::min(e.min_between, from.min_between);
    e.max_between = std::max(e.max_between, from.max_between);
    e.min_gap2 = std::min(e.min_gap2, from.min_gap2);
  };
  springs_from_sweeps_ = spring_scan_sweep_ == sweep_;
  if (springs_from_sweeps_) {
    merge(scratch_[0].extremes);
    merge(scratch_[1].extremes);
  } else {
    SweepScratch& w = scratch_[0];
    for (const int strip : sweep_order_) {
      const std::size_t si = static_cast<std::size_t>(strip);
      const int q0 = band_pair_start_[si], q1 = band_pair_start_[si + 1];
      for (int q = q0; q < q1; ++q)
        w.band_dist2[static_cast<std::size_t>(q - q0)] =
            bandDist2(positions_.data(), band_pairs_[static_cast<std::size_t>(q)]);
      finishStripSprings(si, w.band_dist2.data(), positions_.data(), e, w.band_outside.data());
    }
    finishRootSprings(positions_.data(), e);
  }
  auto ratio = [](double r2, double none) { return r2 == none ? 1.0 : std::sqrt(r2); };
  min_ratio_[0] = ratio(e.min_between, 1e300), max_ratio_[0] = ratio(e.max_between, 0.0);
  min_ratio_[1] = ratio(e.min_within, 1e300), max_ratio_[1] = ratio(e.max_within, 0.0);
  min_gap_ = e.min_gap2 == 1e300 ? 0.0 : std::sqrt(e.min_gap2);
}

std::vector<Ellipsoid> Simulator::bodiesInHeadFrame(const Iso3& head_pose, const std::vector<Iso3>& frames,
                                                    double margin) const {
  if (frames.size() != bodies_.size())
    throw std::invalid_argument("Simulator::bodiesInHeadFrame(...) : " + std::to_string(frames.size()) +
                                " body frame poses for " + std::to_string(bodies_.size()) + " bodies");
  std::vector<Ellipsoid> out;
  out.reserve(bodies_.size());
  const Iso3 head_inv = head_pose.inverse();
  for (std::size_t b = 0; b < bodies_.size(); ++b)
    out.push_back(bodies_[b].shape.inflated(margin).transformed(head_inv * frames[b]));
  return out;
}

namespace {

/// The bracket's width (rad) at which escapeBodies stops: the end of a segment of length d then lies within
/// d * 2^-33 (1.2e-11 m for 0.1 m) of the edge of the clear range it found.
constexpr double kEscapeTolerance = 0x1p-33;

/// Does the straight path q0 -> q1 (sphere space) enter the unit sphere from outside? c0 = |q0|^2 - 1 (as
/// q0.squaredNorm() - 1.0: prepareBodies keeps it per body, the same for every direction probed).
bool pathEntersUnitSphere(const Vec3& q0, double c0, const Vec3& q1) {
  const double c = c0;
  if (c <= 0.0) return false;  // starts inside: not an entry (handled as "inside")
  const Vec3 d = q1 - q0;
  const double a = d.squaredNorm();
  if (a < 1e-300) return false;
  const double b = q0.dot(d);
  if (b >= 0.0) return false;  // moving away
  const double disc = b * b - a * c;
  if (disc < 0.0) return false;
  // The entry t = (-b - sqrt(disc)) / a <= 1, i.e. -b - a <= sqrt(disc): without a division or a square
  // root (the lanes test the same way, so both paths decide alike).
  const double lhs = -b - a;
  return lhs <= 0.0 || lhs * lhs <= disc;
}

/// How clear of the unit sphere the straight path q0 -> q1 (sphere space) is by pathEntersUnitSphere's test,
/// for escapeBodies to interpolate: positive when the path does not enter (up to rounding at the boundary),
/// continuous in q1, and of the first order in the direction where the path grazes the sphere (a start on it
/// is the common case: c0 ~ 0, where |q|^2 - 1 along the path would be of the second order). With b = q0.dq,
/// a = |dq|^2: no entry while b + sqrt(a c0) > 0 (moving away, or disc = b^2 - a c0 < 0) or while the entry
/// lies beyond q1 (-b - sqrt(disc) > a); +inf when it starts inside (no entry to test).
double pathClearance(const Vec3& q0, double c0, const Vec3& q1) {
  if (c0 <= 0.0) return std::numeric_limits<double>::infinity();
  const Vec3 d = q1 - q0;
  const double a = d.squaredNorm();
  const double b = q0.dot(d);
  const double disc = b * b - a * c0;
  return std::max(b + std::sqrt(a * c0), -b - a - std::sqrt(std::max(disc, 0.0)));
}

}  // namespace

void Simulator::prepareBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& previous_end,
                              const std::vector<Ellipsoid>& now, const std::vector<Ellipsoid>& before) {
  const std::size_t nb = now.size();
  // In the sphere space of body b the end of direction u is q_pivot + d Sinv u, so the pivot and the
  // previous end are mapped once per point. A body is out of reach when the ball that holds every
  // end, every segment and every path from the previous end (centre q_pivot, radius
  // max(d / smallest radius, |q_prev - q_pivot|)) lies outside the unit sphere: then nothing below
  // can fail for it, and it is skipped.
  w.near.clear();
  w.prepared_previous_end = previous_end;
  if (w.is_near.size() != nb) {  // every entry is set below
    w.is_near.resize(nb);
    w.q_pivot.resize(nb);
    w.q_prev.resize(nb);
    w.c_pivot.resize(nb);
    w.c_prev.resize(nb);
    w.pivot_inside.resize(nb);
    w.near.reserve(nb);
  }
  // First a test in the head frame without the sphere-space maps: with D the distance from the pivot to
  // the centre of the ball of radius R that holds the body, every end and segment lies within d of the
  // pivot, and the path of the previous end, seen from the moving body, runs from p' = M (prev - c_before)
  // + c_now (M = S_now Sinv_before) to the end, where |p' - pivot| <= a + shift + motion (a + D + shift)
  // with a = |prev - pivot|. So the body is out of reach when D > R + d and D (1 - motion) > R + (a +
  // shift)(1 + motion) (compared on squares); R keeps a relative 1e-6 and 1 um to spare.
  const bool quick = w.bounds != nullptr && w.bounds->size() == nb;
  const double a = (quick && !before.empty()) ? (previous_end - pivot).norm() : 0.0;
  for (std::size_t b = 0; b < nb; ++b) {
    if (quick) {
      const BodyBound& bound = (*w.bounds)[b];
      const double dist2 = (pivot - bound.centre).squaredNorm();
      const double reach = bound.radius + d;
      if (dist2 > reach * reach) {
        bool far = true;
        if (!before.empty()) {
          far = bound.motion < 0.5;
          if (far) {
            const double lim = bound.radius + (a + bound.shift) * (1.0 + bound.motion);
            const double keep = 1.0 - bound.motion;
            far = dist2 * (keep * keep) > lim * lim;
          }
        }
        if (far) {
          w.pivot_inside[b] = 0;
          w.is_near[b] = 0;
          continue;
        }
      }
    }
    const Vec3 qp = now[b].toSphere(pivot);
    w.q_pivot[b] = qp;
    const double n2 = qp.squaredNorm();
    w.pivot_inside[b] = n2 < 1.0;
    // Out of reach when |q_pivot| > 1 + max(reach_end, |q_prev - q_pivot|) + 1e-9, tested on squares (a
    // square root only when the first part holds).
    const double lim = 1.0 + d / now[b].radii().minCoeff() + 1e-9;
    bool far = n2 > lim * lim;
    if (!before.empty()) {
      w.q_prev[b] = before[b].toSphere(previous_end);
      if (far) {
        const double spare = std::sqrt(n2) - 1.0 - 1e-9;
        far = (w.q_prev[b] - qp).squaredNorm() < spare * spare;
      }
    }
    w.is_near[b] = far ? 0 : 1;
    if (far) continue;
    w.c_pivot[b] = n2 - 1.0;
    if (!before.empty()) w.c_prev[b] = w.q_prev[b].squaredNorm() - 1.0;
    w.near.push_back(b);
  }
}

Vec3 Simulator::endInSphere(const SweepScratch& w, std::size_t b, double d, const Vec3& u,
                            const std::vector<Ellipsoid>& now) const {
  return w.q_pivot[b] + d * (now[b].Sinv() * u);
}

int Simulator::failedKind(const SweepScratch& w, std::size_t b, const Vec3& q_end, bool have_before) const {
  if (q_end.squaredNorm() - 1.0 <= 1e-12) return 0;
  if (w.pivot_inside[b] || w.clear_level >= 2) return -1;  // a root inside its scalp: only the end counts
  if (pathEntersUnitSphere(w.q_pivot[b], w.c_pivot[b], q_end)) return 1;  // the segment cuts through
  if (have_before && w.clear_level == 0 && pathEntersUnitSphere(w.q_prev[b], w.c_prev[b], q_end)) return 2;
  return -1;
}

bool Simulator::clearOf(const SweepScratch& w, std::size_t b, double d, const Vec3& u,
                        const std::vector<Ellipsoid>& now, bool have_before) const {
  return !w.is_near[b] || failedKind(w, b, endInSphere(w, b, d, u, now), have_before) < 0;
}

double Simulator::testMargin(const SweepScratch& w, std::size_t b, int kind, const Vec3& q_end) const {
  if (kind == 0) return (q_end.squaredNorm() - 1.0) - 1e-12;
  return kind == 1 ? pathClearance(w.q_pivot[b], w.c_pivot[b], q_end)
                   : pathClearance(w.q_prev[b], w.c_prev[b], q_end);
}

Simulator::EscapeProbe Simulator::probeEscape(const SweepScratch& w, double d, const Vec3& u,
                                              const std::vector<Ellipsoid>& now, bool have_before,
                                              std::size_t follow_body, int follow_kind) const {
  EscapeProbe p;
  for (std::size_t b : w.near) {
    const Vec3 q_end = endInSphere(w, b, d, u, now);
    if (b == follow_body && follow_kind >= 0) p.margin = testMargin(w, b, follow_kind, q_end);
    if (p.kind < 0) {
      p.kind = failedKind(w, b, q_end, have_before);
      p.body = b;
    }
  }
  return p;
}

bool Simulator::clearOfAll(const SweepScratch& w, double d, const Vec3& u, const std::vector<Ellipsoid>& now,
                           bool have_before) const {
  for (std::size_t b : w.near)
    if (!clearOf(w, b, d, u, now, have_before)) return false;
  return true;
}

Vec3 Simulator::clearBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& dir,
                            const std::vector<Ellipsoid>& now, bool have_before, int first_level) {
  // Validity for one body: end outside, segment not cutting through it (pivot outside), and the end's
  // path over the substep, relative to the moving body, not entering it (the paper's ray test).
  auto validBodies = [&](const Vec3& u) { return clearOfAll(w, d, u, now, have_before); };
  w.clear_level = first_level;
  Vec3 result = dir;
  if (!validBodies(dir)) {
    ++w.collisions;
    result = escapeBodies(w, pivot, d, dir, now, have_before);
    // No direction passes every test (a crevice between bodies moving fast, where every end's path over
    // the substep crosses one): the end outside every body comes first, so the swept test goes, then the
    // segment test (the hard guarantee is on where the points are after the substep).
    for (++w.clear_level; w.clear_level <= 2 && !validBodies(result); ++w.clear_level)
      result = escapeBodies(w, pivot, d, result, now, have_before);
  }
  w.clear_level = 0;
  return result;
}

namespace {
/// resolveCollisions' walk round the band's circle: step k at the angle (pi / 16) ((k + 1) / 2) (-1 for even
/// k, +1 for odd), its cosine and sine computed once (std::cos, std::sin: the values the walk computed each
/// time before).
constexpr int kCircleSteps = 32;
struct CircleStep {
  double cos, sin;
};
const CircleStep* circleSteps() {
  static const std::array<CircleStep, kCircleSteps + 1> steps = [] {
    std::array<CircleStep, kCircleSteps + 1> t{};
    for (int k = 0; k <= kCircleSteps; ++k) {
      const double angle = (kPi / 16.0) * ((k + 1) / 2) * (k % 2 ? 1.0 : -1.0);
      t[static_cast<std::size_t>(k)] = {std::cos(angle), std::sin(angle)};
    }
    return t;
  }();
  return steps.data();
}
}  // namespace

Vec3 Simulator::resolveCollisions(SweepScratch& w, int point, const Vec3& pivot, double d, const Vec3& dir,
                                  const std::vector<Ellipsoid>& now, const std::vector<Ellipsoid>& before) {
  auto validBodies = [&](const Vec3& u) { return clearOfAll(w, d, u, now, !before.empty()); };
  const Vec3 result = clearBodies(w, pivot, d, dir, now, !before.empty());
  // Spring band as a constraint: move the end into [contact, far] x rest length of each partner
  // (a few projection sweeps, the length to the pivot kept), if that keeps clear of the bodies.
  const int p_begin = partner_start_[static_cast<std::size_t>(point)];
  const int p_end = partner_start_[static_cast<std::size_t>(point) + 1];
  if (p_begin == p_end) return result;
  // Projects the end of direction u into every band (sweeps); returns whether anything moved. `settled`: the
  // last sweep moved nothing (every band holds at the u returned), not the cap of 8 sweeps.
  bool settled = false;
  auto project = [&](Vec3& u) {
    bool moved = false;
    settled = false;
    for (int sweep = 0; sweep < 8; ++sweep) {
      bool any = false;
      for (int q = p_begin; q < p_end; ++q) {
        // Each pair is kept by the later of its two points in the sweep, against the final position
        // of the earlier one: partners not yet moved in this substep keep the pair themselves.
        const Vec3* placed = placedPartner(w, static_cast<std::size_t>(q));
        if (!placed) continue;
        const Vec3& other = *placed;
        const Vec3 end = pivot + d * u;
        const double r = bandTarget((end - other).norm(), partner_rest_[static_cast<std::size_t>(q)]);
        if (r == 0.0) continue;
        // Nearest point to `end` on the circle where the sphere |x - pivot| = d meets |x - other| = r.
        const Vec3 po = other - pivot;
        const double L = po.norm();
        if (L < 1e-12) continue;
        const Vec3 axis = po / L;
        const double h = (d * d - r * r + L * L) / (2.0 * L);
        if (std::abs(h) >= d) {
          // No such circle: the band cannot be met from this pivot. Come as close to it as the
          // segment allows (straight toward the partner, or straight away from it), if that is clear.
          const Vec3 best = h >= d ? axis : Vec3(-axis);
          if ((best - u).squaredNorm() > 1e-24 && validBodies(best)) u = best, any = true;
          continue;
        }
        const double rho = std::sqrt(d * d - h * h);
        Vec3 perp = (end - pivot) - (end - pivot).dot(axis) * axis;
        const double perp_norm = perp.norm();  // (normalize() divides by this same square root)
        if (perp_norm < 1e-12) {
          perp = axis.unitOrthogonal();
          perp.normalize();
        } else {
          perp /= perp_norm;
        }
        // The nearest point of the circle first; if a body is in the way, the points of the circle
        // farther and farther round from it (steps of pi/16 each way) until one is clear.
        // (None clear: the nearest point, computed only then.)
        const Vec3 side = axis.cross(perp);
        const CircleStep* steps = circleSteps();
        bool found = false;
        for (int k = 0; k <= kCircleSteps; ++k) {
          const CircleStep& step = steps[k];
          const Vec3 cand = (h * axis + rho * (step.cos * perp + step.sin * side)).normalized();
          if (validBodies(cand)) {
            u = cand;
            found = true;
            break;
          }
        }
        if (!found) u = (h * axis + rho * perp).normalized();
        any = true;
      }
      if (!any) {
        settled = true;
        break;
      }
      moved = true;
    }
    return moved;
  };
  // Alternate between the bands and the bodies; the bodies always have the last word (every
  // direction returned is clear of them).
  Vec3 u = result;  // clear of the bodies
  for (int round = 0; round < 4; ++round) {
    Vec3 p = u;
    if (!project(p)) break;  // every band holds
    if (!validBodies(p)) {
      p = escapeBodies(w, pivot, d, p, now, !before.empty());
      if (!validBodies(p)) break;
    } else if (settled) {
      // Every band holds at p (project's last sweep), which is clear: the next round's project(p) would
      // repeat that sweep, move nothing and stop here.
      return p;
    }
    u = p;
  }
  return u;
}

namespace {
/// escapeBodies' search of the sphere of directions about its first candidate: 13 rings at polar angles pi k
/// / 12 (one direction at each pole, 24 around the others), their cosines and sines computed once.
struct SphereDirection {
  double cos_polar, sin_polar, cos_az, sin_az;
};
const std::vector<SphereDirection>& sphereDirections() {
  static const std::vector<SphereDirection> table = [] {
    std::vector<SphereDirection> t;
    for (int ring = 0; ring <= 12; ++ring) {
      const double polar = kPi * ring / 12.0;
      const int around = ring == 0 || ring == 12 ? 1 : 24;
      for (int j = 0; j < around; ++j) {
        const double az = 2.0 * kPi * j / around;
        t.push_back({std::cos(polar), std::sin(polar), std::cos(az), std::sin(az)});
      }
    }
    return t;
  }();
  return table;
}
}  // namespace

Vec3 Simulator::escapeBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& dir,
                             const std::vector<Ellipsoid>& now, bool have_before) const {
  const std::size_t nb = now.size();
  auto validFor = [&](std::size_t b, const Vec3& u) { return clearOf(w, b, d, u, now, have_before); };
  auto validBodies = [&](const Vec3& u) { return clearOfAll(w, d, u, now, have_before); };
  // The valid direction closest to `dir` on the arc dir -> to (`to` valid): a bracket [lo blocked, hi clear]
  // narrowed until it is at most kEscapeTolerance wide (as the chord |hi - lo|), hi returned. The first
  // midpoint is the normalised sum of the ends, or by rotation for an arc near pi long; after it the arc is
  // at most pi / 2 long and its points are normalised weighted sums of its unit ends (|lo + hi| >= sqrt 2):
  // no sine or cosine per probe. Then the ITP method (Oliveira and Takahashi, ACM TOMS 47(1), 2020) on
  // testMargin of the test that lo fails (smooth and of the first order at its edge): regula falsi, truncated
  // toward the midpoint and projected into a range about it that keeps the probes within one of a
  // bisection's. Each probe is put on its side by the tests themselves (validBodies), so hi is always clear;
  // where lo passes the test followed so far, the test it fails is followed instead. 7.3-7.6 probes where the
  // bisection took 35.6 (docs/benchmarks.md).
  auto nearestClear = [&](const Vec3& to) {
    Vec3 lo = dir.normalized();
    Vec3 hi = to.normalized();
    // (|lo + hi|^2 > 0.01: an arc shorter than 174 degrees.)
    const Vec3 sum = lo + hi;
    const Vec3 half = sum.squaredNorm() > 0.01
                          ? Vec3(sum.normalized())
                          : Vec3(rotateByVector(0.5 * rotationVectorBetween(lo, hi), lo).normalized());
    (validBodies(half) ? hi : lo) = half;
    double width = (hi - lo).norm();
    const EscapeProbe at_lo =
        width > kEscapeTolerance ? probeEscape(w, d, lo, now, have_before) : EscapeProbe{};
    if (at_lo.kind >= 0) {  // (lo is blocked: always)
      std::size_t body = at_lo.body;
      int kind = at_lo.kind;
      double f_lo = testMargin(w, body, kind, endInSphere(w, body, d, lo, now));
      double f_hi = testMargin(w, body, kind, endInSphere(w, body, d, hi, now));
      const double eps = 0.5 * kEscapeTolerance;
      // The truncation k1 width^2 with k1 = 0.015 / (first width): 6.3-6.6 probes here at 100, 1,000 and
      // 10,000 strips of BM_Step's motion, against 7.8-8.1 with the paper's 0.2 (9.0-10.6 below 0.005).
      const double k1 = 0.015 / width;
      // eps 2^(n_max - j) for probe j, n_max = ceil(log2(width / (2 eps))) + 1 (halved per probe: exact).
      double reach = std::ldexp(eps, static_cast<int>(std::ceil(std::log2(width / kEscapeTolerance))) + 1);
      for (int j = 0; j < 64 && width > kEscapeTolerance; ++j, reach *= 0.5) {
        // Places along the chord: lo at 0, hi at width.
        const double x_half = 0.5 * width;
        const double r = std::max(0.0, reach - x_half);
        const double delta = k1 * width * width;
        const double x_f = (f_lo < 0.0 && f_hi > 0.0) ? width * (f_lo / (f_lo - f_hi)) : x_half;
        const double sigma = x_half >= x_f ? 1.0 : -1.0;
        const double x_t = delta <= std::abs(x_half - x_f) ? x_f + sigma * delta : x_half;
        const double x = std::abs(x_t - x_half) <= r ? x_t : x_half - sigma * r;
        const Vec3 mid = (lo + (x / width) * (hi - lo)).normalized();
        // The tests and the followed test's margin from one mapping of mid per body.
        const EscapeProbe at = probeEscape(w, d, mid, now, have_before, body, kind);
        if (at.kind < 0) {
          hi = mid, f_hi = at.margin;
        } else {
          lo = mid, f_lo = at.margin;
          if (f_lo >= 0.0) {  // lo passes the test followed so far: follow the one it fails
            body = at.body, kind = at.kind;
            f_lo = testMargin(w, body, kind, endInSphere(w, body, d, lo, now));
            f_hi = testMargin(w, body, kind, endInSphere(w, body, d, hi, now));
          }
        }
        width = (hi - lo).norm();
      }
    }
    // (Halvings in case the 64 probes above were not enough; one leaves at most 0.55 of the chord.)
    for (int it = 0; it < 64 && (hi - lo).squaredNorm() > kEscapeTolerance * kEscapeTolerance; ++it) {
      const Vec3 mid = (lo + hi).normalized();
      (validBodies(mid) ? hi : lo) = mid;
    }
    return hi;
  };
  // Candidate escape directions: for each violated body, the outward normal of its level set through the
  // pivot (the implicit function's gradient: the body's implicit value grows along the whole ray from a pivot
  // outside, so pivot + d N clears a convex body), or from a pivot inside the normal at its nearest surface
  // point; and their mean (a crevice between two bodies).
  Vec3 cand[8];
  int count = 0;
  Vec3 sum = Vec3::Zero();
  for (std::size_t b = 0; b < nb && count < 7; ++b) {
    if (validFor(b, dir)) continue;
    cand[count] = w.pivot_inside[b] ? now[b].closestPoint(pivot).normal : now[b].normalAt(pivot);
    sum += cand[count++];
  }
  if (count == 0) return dir;
  if (count > 1 && sum.norm() > 1e-9) cand[count++] = sum.normalized();
  for (int c = 0; c < count; ++c)
    if (validBodies(cand[c])) return nearestClear(cand[c]);
  // No single escape clears every body (a pinch between overlapping bodies): search the sphere of
  // directions around the pivot for a valid one, else the one with the smallest worst penetration. The
  // search is remembered for the sweep (w.pinch_searches): relaxStrip repeats it for the same point.
  const Vec3 base = cand[count - 1];
  // (HAIR_SIM_NO_PINCH_MEMORY: every search anew, for the test PinchMemoryGivesTheSameBits.)
#if !defined(HAIR_SIM_NO_PINCH_MEMORY)
  for (const PinchSearch& s : w.pinch_searches) {
    if (s.sweep == sweep_ && s.bodies == now.data() && s.pivot == pivot && s.d == d &&
        s.previous_end == w.prepared_previous_end && s.base == base && s.level == w.clear_level &&
        s.have_before == have_before)
      return s.found ? nearestClear(s.result) : s.result;
  }
  PinchSearch& memo = w.pinch_searches[static_cast<std::size_t>(w.pinch_next)];
  w.pinch_next = (w.pinch_next + 1) % kPinchSearches;
#else
  PinchSearch memo;
#endif
  memo = PinchSearch{};
  memo.sweep = sweep_;
  memo.bodies = now.data();
  memo.pivot = pivot;
  memo.d = d;
  memo.previous_end = w.prepared_previous_end;
  memo.base = memo.result = base;
  memo.level = w.clear_level;
  memo.have_before = have_before;
  double best_depth = 1e300;
  const Vec3 t1 = base.unitOrthogonal(), t2 = base.cross(t1);
  for (const SphereDirection& s : sphereDirections()) {
    const Vec3 u = s.cos_polar * base + s.sin_polar * (s.cos_az * t1 + s.sin_az * t2);
    if (validBodies(u)) {
      memo.found = true;
      memo.result = u;
      return nearestClear(u);
    }
    double worst = 0.0;
    for (std::size_t b = 0; b < nb; ++b)
      worst = std::max(worst, std::max(0.0, -now[b].implicitValue(pivot + d * u)));
    if (worst < best_depth) best_depth = worst, memo.result = u;
  }
  return memo.result;
}

bool Simulator::stripOutsideBand(const SweepScratch& w, std::size_t strip) const {
  const Strip& s = hairstyle_.strips[strip];
  for (int r = 1; r < s.rows; ++r)
    if (rowOutsideBand(w, strip, r)) return true;
  return false;
}

bool Simulator::rowOutsideBand(const SweepScratch& w, std::size_t strip, int row) const {
  return rowBandSide(w, strip, row) != 0;
}

int Simulator::rowBandSide(const SweepScratch& w, std::size_t strip, int row) const {
  const Strip& s = hairstyle_.strips[strip];
  const std::size_t begin = static_cast<std::size_t>(strip_offset_[strip] + s.index(row, 0));
  const std::size_t end = begin + static_cast<std::size_t>(s.columns);
  // relaxStrip may hold a row's far edge to that of the rows below it (w.tighten_to).
  const int to = w.tighten_to.empty() ? row : w.tighten_to[static_cast<std::size_t>(row)];
  int side = 0;
  for (std::size_t i = begin; i < end; ++i)
    for (int q = partner_start_[i]; q < partner_start_[i + 1]; ++q) {
      const double rest = partner_rest_[static_cast<std::size_t>(q)];
      if (rest <= 0.0) continue;  // between strips
      const std::size_t j = static_cast<std::size_t>(partner_index_[static_cast<std::size_t>(q)]);
      if (j < i) continue;  // each pair once (both ends are in this row)
      double far_rest = rest;
      for (int r = row + 1; r <= to; ++r) {
        const std::size_t step = static_cast<std::size_t>((r - row) * s.columns);
        far_rest = std::min(far_rest, withinRest(i + step, j + step, far_rest));
      }
      const int here = bandSide((positions_[i] - positions_[j]).norm(), rest, far_rest);
      if (here != 0 && side != 0 && here != side) return 2;
      if (here != 0) side = here;
    }
  return side;
}

double Simulator::bandTarget(double dist, double signed_rest) const {
  const double rest = std::abs(signed_rest);
  const double contact = contactFactor();
  if (dist < contact * rest) return contact * rest * 1.000001;
  // A strip's width stays within the band; between strips only the spring force attracts.
  if (signed_rest > 0.0 && dist > params_.spring_far_factor * rest)
    return params_.spring_far_factor * rest * 0.999999;
  return 0.0;
}

int Simulator::bandSide(double dist, double rest, double far_rest) const {
  if (dist > params_.spring_far_factor * far_rest * (1.0 + 1e-10)) return 1;
  return dist < contactFactor() * rest ? -1 : 0;
}

double Simulator::withinRest(std::size_t i, std::size_t j, double fallback) const {
  for (int q = partner_start_[i]; q < partner_start_[i + 1]; ++q)
    if (static_cast<std::size_t>(partner_index_[static_cast<std::size_t>(q)]) == j &&
        partner_rest_[static_cast<std::size_t>(q)] > 0.0)
      return partner_rest_[static_cast<std::size_t>(q)];
  return fallback;
}

void Simulator::relaxStrip(SweepScratch& w, std::size_t strip, const std::vector<Ellipsoid>& now,
                           const std::vector<Ellipsoid>& before) {
  const Strip& s = hairstyle_.strips[strip];
  const int offset = strip_offset_[strip];
  const int saved_collisions = w.collisions;
  for (int pass = 0; pass < 8 && stripOutsideBand(w, strip); ++pass) {
    for (int c = 0; c < s.columns; ++c) {
      for (int r = 1; r < s.rows; ++r) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const Vec3& pivot = positions_[static_cast<std::size_t>(offset + s.index(r - 1, c))];
        const std::size_t local = static_cast<std::size_t>(s.index(r, c));
        prepareBodies(w, pivot, length_[i], w.start_pos[local], now, before);
        direction_[i] =
            resolveCollisions(w, static_cast<int>(i), pivot, length_[i], direction_[i], now, before);
        positions_[i] = pivot + length_[i] * direction_[i];
      }
    }
  }
  // Gauss-Seidel moves one end at a time, so when two columns cross (the end of one next to the pivot
  // of the other), or when the pivots are as far apart as their own row's band allows and the rest width
  // narrows toward the tips, no single move meets the band, though a joint one does: parallel segments
  // keep the distances of their pivots, and turning them toward each other (or apart) brings their ends
  // closer (or farther) continuously. So, from the roots out, a row still outside the band gets the
  // directions place(mu) below for the first mu of 0, +-1/32, +-2/32, ..., +-1 that puts the row within
  // the band once each segment has been turned clear of the bodies (clearBodies: an end pressed against
  // a body slides along it); if none does, the row keeps what the passes left. The bodies keep the last
  // word: every row, moved or not, is cleared of them from its (possibly moved) pivots.
  const bool crossed = stripOutsideBand(w, strip);
  const bool have_before = !before.empty();
  w.row_dirs.resize(static_cast<std::size_t>(s.columns));
  w.tighten_to.resize(static_cast<std::size_t>(s.rows));
  for (int r = 0; r < s.rows; ++r) w.tighten_to[static_cast<std::size_t>(r)] = r;
  for (int r = 1; crossed && r < s.rows; ++r) {
    auto at = [&](int c) { return static_cast<std::size_t>(offset + s.index(r, c)); };
    auto pivotOf = [&](int c) -> const Vec3& {
      return positions_[static_cast<std::size_t>(offset + s.index(r - 1, c))];
    };
    // Ends at the directions given, each turned clear of the bodies from its pivot; false when an end
    // stays inside a body.
    int level = 0;  // clearBodies' first level: 1 = without the swept test
    auto settle = [&]() {
      bool outside = true;
      for (int c = 0; c < s.columns; ++c) {
        const double d = length_[at(c)];
        if (!now.empty()) {
          prepareBodies(w, pivotOf(c), d, w.start_pos[static_cast<std::size_t>(s.index(r, c))], now, before);
          direction_[at(c)] = clearBodies(w, pivotOf(c), d, direction_[at(c)], now, have_before, level);
          w.clear_level = 2;
          outside = outside && clearOfAll(w, d, direction_[at(c)], now, have_before);
          w.clear_level = 0;
        }
        positions_[at(c)] = pivotOf(c) + d * direction_[at(c)];
      }
      return outside;
    };
    settle();
    if (!rowOutsideBand(w, strip, r)) continue;
    Vec3 mean = Vec3::Zero(), centre = Vec3::Zero();
    for (int c = 0; c < s.columns; ++c) {
      mean += direction_[at(c)];
      centre += pivotOf(c);
      w.row_dirs[static_cast<std::size_t>(c)] = direction_[at(c)];
    }
    centre /= s.columns;
    // Inward (mu > 0): toward directions whose ends all meet, d u = d sqrt(1 - (s/d)^2) a + s e with e the
    // unit vector to the centre, s the distance to it and a the part of m across e: the ends close in
    // continuously from the pivots' distances (mu = 0, parallel) to 0 (mu = 1). Outward (mu < 0):
    // m - |mu| e, the ends move apart.
    auto place = [&](const Vec3& m, double mu) {
      for (int c = 0; c < s.columns; ++c) {
        const double d = length_[at(c)];
        const Vec3 to_centre = centre - pivotOf(c);
        const double dist = to_centre.norm();
        Vec3 u = m;
        if (dist > 1e-12) {
          const Vec3 e = to_centre / dist;
          if (mu < 0.0) {
            u = m + mu * e;
          } else {
            Vec3 across = m - m.dot(e) * e;
            across = across.norm() > 1e-9 ? Vec3(across.normalized()) : Vec3(e.unitOrthogonal());
            const double f = std::min(1.0, dist / d);
            u = (1.0 - mu) * m + mu * (std::sqrt(1.0 - f * f) * across + f * e);
          }
          if (u.norm() < 1e-12) u = m;
        }
        direction_[at(c)] = u.normalized();
      }
      return settle();
    };
    // The common direction m: the mean of the row's directions first; when the columns point far apart
    // (a strip torn open by a violent input) that mean can point into a body, so then each column's own
    // direction in turn. When bodies move so fast that the swept test leaves no joint placement (a nod of
    // pi/2 at 20 Hz moves the torso 0.25 m in a substep), the placements are tried again without it: the
    // ends still land outside every body.
    bool found = false;
    for (int candidate = -1; !found; ++candidate) {
      if (candidate == s.columns) {
        if (level == 1 || before.empty()) break;
        level = 1;
        candidate = -1;
      }
      const Vec3 m = candidate < 0 ? mean : w.row_dirs[static_cast<std::size_t>(candidate)];
      if (m.norm() < 1e-9) continue;
      const Vec3 mn = m.normalized();
      // A body can deflect an end so that the row's width jumps over the band between two steps of mu
      // (too wide at one, too narrow at the next): then the band is looked for by bisection between them.
      double last_mu[2] = {0.0, 0.0};
      int last_side[2] = {3, 3};  // per direction (outward, inward); 3 = none yet
      for (int k = 0; k <= 64 && !found; ++k) {
        const double mu = ((k + 1) / 2) * (k % 2 ? 1.0 : -1.0) / 32.0;
        const int side = place(mn, mu) ? rowBandSide(w, strip, r) : 3;
        found = side == 0;
        for (int dir = 0; dir < 2 && !found; ++dir) {
          if (k != 0 && (k % 2) != dir) continue;  // mu = 0 starts both directions
          if (std::abs(side) == 1 && std::abs(last_side[dir]) == 1 && side != last_side[dir]) {
            double a = last_mu[dir], b = mu;  // side(a) = last_side, side(b) = side
            for (int it = 0; it < 24 && !found; ++it) {
              const double mid = 0.5 * (a + b);
              const int mid_side = place(mn, mid) ? rowBandSide(w, strip, r) : 3;
              found = mid_side == 0;
              if (mid_side == last_side[dir])
                a = mid;
              else if (mid_side == side)
                b = mid;
              else
                break;
            }
          }
          last_mu[dir] = mu;
          last_side[dir] = side;
        }
      }
    }
    if (found) continue;
    for (int c = 0; c < s.columns; ++c) {  // back to what the passes left (cleared of the bodies above)
      direction_[at(c)] = w.row_dirs[static_cast<std::size_t>(c)];
      positions_[at(c)] = pivotOf(c) + length_[at(c)] * direction_[at(c)];
    }
    // A body keeps the ends of this row from closing in far enough from where the row above put its
    // pivots (a strip draped over a body, its rest width narrowing toward the tips): the row above is
    // held to this row's far edge too, so that parallel segments meet it here, and both are placed again.
    const std::size_t above = static_cast<std::size_t>(r - 1);
    if (r >= 2 && w.tighten_to[above] < w.tighten_to[static_cast<std::size_t>(r)]) {
      w.tighten_to[above] = w.tighten_to[static_cast<std::size_t>(r)];
      r -= 2;  // the loop's ++r: row r - 1 again
    }
  }
  w.tighten_to.clear();
  w.collisions = saved_collisions;  // the sweep counted the segments turned out of a body
  const double dt = params_.substep;
  for (int r = 1; r < s.rows; ++r)
    for (int c = 0; c < s.columns; ++c) {
      const std::size_t local = static_cast<std::size_t>(s.index(r, c));
      const std::size_t i = static_cast<std::size_t>(offset) + local;
      const Vec3& pivot = positions_[static_cast<std::size_t>(offset + s.index(r - 1, c))];
      rate_[i] = rotationVectorBetween(w.start_dir[local], direction_[i]);
      const Vec3 mid = pivot + 0.5 * length_[i] * direction_[i];
      velocity_[i] = (mid - w.start_mid[local]) / dt;
    }
}

void Simulator::setShape(const std::vector<Vec3>& target) {
  if (target.size() != positions_.size())
    throw std::invalid_argument("Simulator::setShape(...) : " + std::to_string(target.size()) +
                                " points given, the hairstyle has " + std::to_string(positions_.size()));
  for (std::size_t i = 0; i < target.size(); ++i)
    if (!target[i].allFinite())
      throw std::invalid_argument("Simulator::setShape(...) : point " + std::to_string(i) + " is not finite");
  spring_scan_sweep_ = -1;  // (the hair moves: the next scan reads the points)
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int c = 0; c < s.columns; ++c) {
      std::size_t parent = static_cast<std::size_t>(offset + s.index(0, c));
      for (int r = 1; r < s.rows; ++r) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const Vec3 seg = target[i] - target[parent];
        if (seg.norm() > 1e-12) direction_[i] = seg.normalized();
        positions_[i] = positions_[parent] + length_[i] * direction_[i];
        rate_[i].setZero();
        velocity_[i].setZero();
        parent = i;
      }
    }
    offset += s.pointCount();
  }
}

namespace {
/// Throws std::invalid_argument naming the first non-finite input of a substep (before it changes anything).
void checkStepInputs(const StepInputs& in) {
  auto vec = [](const char* what, const Vec3& v) {
    if (v.allFinite()) return;
    throw std::invalid_argument(std::string("Simulator::step(...) : ") + what + " is (" +
                                formatDouble(v.x()) + ", " + formatDouble(v.y()) + ", " +
                                formatDouble(v.z()) + "): not finite, the substep is not taken");
  };
  auto badPose = [](const std::string& what) {
    return std::invalid_argument("Simulator::step(...) : " + what +
                                 " has non-finite entries: the substep is not taken");
  };
  if (!in.head.pose.matrix().allFinite()) throw badPose("head.pose");
  vec("head.linear_velocity", in.head.linear_velocity);
  vec("head.linear_acceleration", in.head.linear_acceleration);
  vec("head.angular_velocity", in.head.angular_velocity);
  vec("head.angular_acceleration", in.head.angular_acceleration);
  vec("wind", in.wind);
  if (in.gravity) vec("gravity", *in.gravity);
  for (std::size_t b = 0; b < in.body_frames.size(); ++b)
    if (!in.body_frames[b].matrix().allFinite()) throw badPose("body_frames[" + std::to_string(b) + "]");
}
}  // namespace

void Simulator::step(const StepInputs& in) {
  checkStepInputs(in);
  StepFrame f;
  f.dt = params_.substep;
  f.rho = params_.linear_density;
  f.k = params_.hinge_stiffness;
  f.gamma = params_.hinge_damping;
  f.drag = params_.air_drag;
  // Slightly above cos(max_bend), so that rounding never skips an angle just over the limit.
  f.cos_max_bend = std::cos(params_.max_bend) + 1e-12;
  f.Rt = in.head.pose.linear().transpose();
  // World quantities seen from the head frame.
  const Vec3 g = f.Rt * (in.gravity ? *in.gravity : params_.gravity);
  f.turbulent = in.turbulence && !in.turbulence->empty();
  const Vec3 acc0 = f.Rt * in.head.linear_acceleration;
  const Vec3 omega = f.Rt * in.head.angular_velocity;
  const Vec3 alpha = f.Rt * in.head.angular_acceleration;
  const Vec3 air0 =
      f.Rt * (in.wind - in.head.linear_velocity);  // air velocity at the head origin, head frame
  // (6) per metre of segment: rho (g + a) + drag (air - v) with the fictitious acceleration of the head frame
  // a = -a0 - alpha x m - omega x (omega x m) - 2 omega x v and the air air0 - omega x m at the midpoint m.
  auto crossMatrix = [](const Vec3& w) {
    Mat3 c;
    c << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
    return c;
  };
  const Mat3 omega_x = crossMatrix(omega);
  f.force0 = f.rho * (g - acc0) + f.drag * air0;
  f.force_mid = -f.rho * (crossMatrix(alpha) + omega_x * omega_x) - f.drag * omega_x;
  f.force_vel = -2.0 * f.rho * omega_x - f.drag * Mat3::Identity();
  f.k_c = params_.collision_stiffness;
  f.c_c = params_.collision_damping;
  collisions_ = 0;
  if (!bodies_.empty()) {
    bodies_now_.resize(margins_.size());
    for (std::size_t m = 0; m < margins_.size(); ++m)
      bodies_now_[m] = bodiesInHeadFrame(in.head.pose, in.body_frames, margins_[m]);
  }
  springs_from_sweeps_ = false;
  if (!springs_.empty()) computeSpringForces();
  if (!bodies_.empty()) {
    body_bounds_.resize(margins_.size());
    for (std::size_t m = 0; m < margins_.size(); ++m) {
      const std::vector<Ellipsoid>& now = bodies_now_[m];
      std::vector<BodyBound>& bounds = body_bounds_[m];
      bounds.resize(now.size());
      for (std::size_t b = 0; b < now.size(); ++b) {
        BodyBound& bound = bounds[b];
        bound.centre = now[b].center();
        bound.radius = now[b].radii().maxCoeff() * (1.0 + 1e-6) + 1e-6;
        bound.motion = 1.0;
        bound.shift = 0.0;
        if (have_bodies_before_ && m < bodies_before_.size() && b < bodies_before_[m].size()) {
          const Ellipsoid& before = bodies_before_[m][b];
          bound.motion = (now[b].S() * before.Sinv() - Mat3::Identity()).norm();
          bound.shift = (now[b].center() - before.center()).norm();
        }
      }
    }
  }

  for (SweepScratch& w : scratch_) {
    w.tally = StepTally();
    w.collisions = 0;
    w.exact_strips = 0;
  }
  // A new mark for the points and strips placed in this sweep (never reused, even after a step() that threw
  // or a reset()).
  ++sweep_;
  if (step_path_ == StepPath::Exact || lane_point_.empty()) {
    // In the sweep order, each group with its own scratch as stepLanes sweeps them (the same bits).
    for (std::size_t rank = 0; rank < sweep_order_.size(); ++rank) {
      SweepScratch& w = scratch_[rank >= sweep_group_end_[0] && rank < sweep_group_end_[1] ? 1 : 0];
      const std::size_t si = static_cast<std::size_t>(sweep_order_[rank]);
      stepStrip(w, in, f, si, strip_offset_[si], w.tally);
      ++w.exact_strips;
    }
  } else {
    stepLanes(in, f);
  }
  StepTally tally;
  exact_strips_ = 0;
  for (SweepScratch& w : scratch_) {
    w.bounds = nullptr;
    tally.max_rate = std::max(tally.max_rate, w.tally.max_rate);
    tally.max_rate2 = std::max(tally.max_rate2, w.tally.max_rate2);
    tally.max_penetration = std::max(tally.max_penetration, w.tally.max_penetration);
    tally.penetrations += w.tally.penetrations;
    collisions_ += w.collisions;
    exact_strips_ += w.exact_strips;
  }
  max_rate_ = std::max(tally.max_rate, std::sqrt(tally.max_rate2) / f.dt);
  max_penetration_ = tally.max_penetration;
  penetrations_ = tally.penetrations;
  if (!bodies_.empty()) {
    bodies_before_ = bodies_now_;
    have_bodies_before_ = true;
  }
  ++steps_;
}

namespace {
/// force0 + force_mid m + force_vel v (StepFrame), in the lanes kernel's order of operations.
Vec3 linearForce(const Vec3& force0, const Mat3& force_mid, const Mat3& force_vel, const Vec3& m,
                 const Vec3& v) {
  Vec3 out;
  for (int r = 0; r < 3; ++r)
    out[r] = (force0[r] + (force_mid(r, 0) * m.x() + force_mid(r, 1) * m.y() + force_mid(r, 2) * m.z())) +
             (force_vel(r, 0) * v.x() + force_vel(r, 1) * v.y() + force_vel(r, 2) * v.z());
  return out;
}
}  // namespace

void Simulator::stepStrip(SweepScratch& w, const StepInputs& in, const StepFrame& f, std::size_t si,
                          int offset, StepTally& tally, int from, bool from_lanes) {
  const double dt = f.dt, k = f.k, gamma = f.gamma, drag = f.drag;
  const double cos_max_bend = f.cos_max_bend, k_c = f.k_c, c_c = f.c_c;
  const Mat3& Rt = f.Rt;
  const bool turbulent = f.turbulent;
  static const std::vector<Ellipsoid> kNone;
  const Strip& s = hairstyle_.strips[si];
  w.sweep_rank = strip_rank_[si];
  const std::vector<Ellipsoid>& bodies_now =
      bodies_.empty() ? kNone : bodies_now_[static_cast<std::size_t>(margin_of_strip_[si])];
  const std::vector<Ellipsoid>& bodies_before =
      (bodies_.empty() || !have_bodies_before_)
          ? kNone
          : bodies_before_[static_cast<std::size_t>(margin_of_strip_[si])];
  w.bounds = bodies_.empty() ? nullptr : &body_bounds_[static_cast<std::size_t>(margin_of_strip_[si])];
  // The strip at the start of the substep for relaxStrip (rows >= 1, filled as the sweep moves them).
  const std::size_t count = static_cast<std::size_t>(s.pointCount());
  if (w.start_pos.size() < count) {
    w.start_pos.resize(count);
    w.start_dir.resize(count);
    w.start_mid.resize(count);
    w.free_dir.resize(count);
  }
  // The within-strip band (stripOutsideBand), checked as the sweep places the later point of each pair.
  const bool check_band = params_.springs_within_strips;
  bool outside_band = false;
  // rowOutsideBand's test for the pairs of point i whose other point is already in place.
  auto checkBand = [&](std::size_t i) {
    if (!check_band || outside_band) return;
    for (int q = partner_start_[i]; q < partner_start_[i + 1]; ++q) {
      const double rest = partner_rest_[static_cast<std::size_t>(q)];
      if (rest <= 0.0) continue;  // between strips
      const std::size_t j = static_cast<std::size_t>(partner_index_[static_cast<std::size_t>(q)]);
      if (moved_in_step_[j] != sweep_) continue;  // kept when j is placed
      if (bandSide((positions_[i] - positions_[j]).norm(), rest, rest) != 0) {
        outside_band = true;
        return;
      }
    }
  };
  // Whether resolveCollisions' band projection would move the end `end` of point i (its first sweep's test).
  auto bandActs = [&](std::size_t i, const Vec3& end) {
    for (int q = partner_start_[i]; q < partner_start_[i + 1]; ++q) {
      const Vec3* placed = placedPartner(w, static_cast<std::size_t>(q));
      if (!placed) continue;
      if (bandTarget((end - *placed).norm(), partner_rest_[static_cast<std::size_t>(q)]) != 0.0) return true;
    }
    return false;
  };
  // Point i's state at the end of the substep: direction `next` from `pivot`, turned by rot.
  w.exact_placed.clear();
  w.exact_relaxed = false;
  auto place = [&](std::size_t i, const Vec3& pivot, double d, const Vec3& next, const Vec3& rot) {
    w.exact_placed.push_back(static_cast<int>(i));
    tally.max_rate2 = std::max(tally.max_rate2, rot.squaredNorm());
    rate_[i] = rot;
    direction_[i] = next;
    positions_[i] = pivot + d * next;
    moved_in_step_[i] = sweep_;
    const Vec3 mid_next = pivot + 0.5 * d * next;
    velocity_[i] = (mid_next - w.start_mid[i - static_cast<std::size_t>(offset)]) / dt;
  };
  // Point i's segment midpoint at the start of the substep, from its parent's start position (row r >= 2:
  // kept in w.start_pos when the sweep reached it; row 1: a root, which never moves) and its own start
  // direction: bit for bit the midpoint the last substep computed as pivot + d/2 direction (place,
  // relaxStrip, the lanes), so it is not stored.
  auto midAtStart = [&](int r, std::size_t parent, std::size_t i, double d) -> Vec3 {
    const Vec3& pivot = r == 1 ? positions_[parent] : w.start_pos[parent - static_cast<std::size_t>(offset)];
    return pivot + 0.5 * d * direction_[i];
  };
  for (int c = 0; c < s.columns; ++c) {
    // The free step (the dynamics before the bend limit and the constraints) of each row is taken from its
    // parent's free step: the forces act at the segment hung from the parent's free end (free_pivot), and the
    // hinge's rest direction is carried by the parents' free directions (w.free_dir). The constraints then
    // place the ends root to tip from the parents' final ends (pivot). Q: the rotation of row q_row's free
    // direction from its styled frame (the rest frame of row q_row + 1), brought down the column only where
    // the exact step needs it.
    Mat3 Q = Mat3::Identity();
    int q_row = 1;
    std::size_t parent = static_cast<std::size_t>(offset + s.index(0, c));
    Vec3 free_pivot = positions_[parent];
    // Whether a point above in this column was placed elsewhere than the lanes' free end (the rows below then
    // hang from another pivot: their free steps hold, their constraints are resolved again), and whether one
    // took the exact step's own dynamics (the rows below then take them too: the free steps differ by its
    // rounding).
    bool diverged = false;
    bool own_dynamics = false;
    // Row r's rest direction, carried by the free directions above it (point i).
    auto restOf = [&](int r, std::size_t i) -> Vec3 {
      if (r == 1) return rest_dir_[i];
      for (; q_row < r; ++q_row) {
        const std::size_t above = static_cast<std::size_t>(s.index(q_row, c));
        Q = minimalRotation(Q * styled_dir_[offset + above], w.free_dir[above]) * Q;
      }
      return Q * rest_dir_[i];
    };
    // The bend limit relative to the rest direction keeps the hinge away from a fold-back (the angle is only
    // needed when the cosine says it may be over the limit).
    auto limitBend = [&](const Vec3& rest, const Vec3& next) -> Vec3 {
      if (rest.dot(next) >= cos_max_bend) return next;
      const Vec3 bend = rotationVectorBetween(rest, next);
      const double bend_angle = bend.norm();
      if (bend_angle > params_.max_bend) return rotateByVector(bend * (params_.max_bend / bend_angle), rest);
      return next;
    };
    for (int r = 1; r < s.rows; ++r) {
      const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
      const std::size_t local = i - static_cast<std::size_t>(offset);
      const bool before_from = c * s.rows + r < from;
      const double d = length_[i];
      if (before_from || (from_lanes && !own_dynamics && !(lane_flag_[i] & lanes::kPointFull))) {
        // The lanes' free step is this point's. Before the place the exact step takes over, it is taken as it
        // is (nothing acted there). After it, the bend limit applies where the lanes flagged it (kPointBend);
        // then a body in the way (kPointBodies), a spring band that the places already final would have
        // projected the end into, a pivot moved above or the bend limit is resolved from it, as the exact
        // step would after its own free step; the start state is kept for relaxStrip.
        w.start_pos[local] = positions_[i];
        w.start_dir[local] = direction_[i];
        w.start_mid[local] = midAtStart(r, parent, i, d);
        const Vec3& free_next = new_direction_[i];
        w.free_dir[local] = free_next;
        free_pivot = new_position_[i];
        const Vec3& pivot = positions_[parent];
        const Vec3 limited =
            (lane_flag_[i] & lanes::kPointBend) ? limitBend(restOf(r, i), free_next) : free_next;
        // (The end as resolveCollisions' band projection computes it, not new_position_: the same bits only
        // while neither file contracts to FMA.)
        if (before_from || (!diverged && limited == free_next && !(lane_flag_[i] & lanes::kPointBodies) &&
                            !bandActs(i, pivot + d * free_next))) {
          tally.max_rate2 = std::max(tally.max_rate2, commitLanes(i));
          if (!before_from) checkBand(i);
          parent = i;
          continue;
        }
        prepareBodies(w, pivot, d, positions_[i], bodies_now, bodies_before);
        const Vec3 next =
            resolveCollisions(w, static_cast<int>(i), pivot, d, limited, bodies_now, bodies_before);
        countPenetration(w, pivot + d * next, bodies_now, tally);
        if (!diverged && next == free_next) {
          tally.max_rate2 = std::max(tally.max_rate2, commitLanes(i));
        } else {
          place(i, pivot, d, next,
                next == free_next ? new_rate_[i] : rotationVectorBetween(direction_[i], next));
          diverged = true;
        }
        checkBand(i);
        parent = i;
        continue;
      }
      diverged = true;  // the exact step's own rounding from here down the column
      own_dynamics = true;
      const double inv_i = inv_inertia_[i];
      const Vec3& pivot = positions_[parent];
      const Vec3 n = direction_[i];
      const Vec3 mid = free_pivot + 0.5 * d * n;
      const Vec3& v = velocity_[i];  // midpoint velocity relative to the head over the last substep
      w.start_pos[local] = positions_[i];
      w.start_dir[local] = n;
      w.start_mid[local] = midAtStart(r, parent, i, d);
      // (6): F = d (rho (g + a) + drag (air - v)) + the springs' force, with the fictitious acceleration a
      // of the head frame (linear, angular, centrifugal, Coriolis) and the drag of the air relative to the
      // hair: linear in the midpoint and its velocity (StepFrame::force0, force_mid, force_vel).
      Vec3 per_metre = linearForce(f.force0, f.force_mid, f.force_vel, mid, v);
      if (turbulent) per_metre += drag * (Rt * in.turbulence->at(in.head.pose * mid));
      Vec3 F = d * per_metre + spring_force_[i];
      // (8)-(10): reaction constraint while the control point is inside an inflated body (only a
      // body within the segment's reach can hold it).
      const Vec3 end_now = free_pivot + d * n;
      prepareBodies(w, free_pivot, d, positions_[i], bodies_now, bodies_before);
      for (std::size_t b : w.near) {
        const Ellipsoid& e = bodies_now[b];
        if ((w.q_pivot[b] + d * (e.Sinv() * n)).squaredNorm() >= 1.0) continue;
        const Ellipsoid::ClosestPoint cp = e.closestPoint(end_now);
        const Vec3 v_end = (end_now - positions_[i]) / dt;
        F = reactionForce(F, -cp.normal, -cp.signed_distance, v_end, k_c, c_c);
      }
      // (4)-(5): moment of F at the lever d/2 about the two axes perpendicular to the segment.
      Vec3 M = 0.5 * d * n.cross(F);
      // (3): hinge spring toward the rest direction carried by the parent.
      const Vec3 rest = restOf(r, i);
      M -= k * rotationVectorBetween(rest, n);  // (both terms are perpendicular to n)
      // (7) corrected: I (w^{n+1} - w^n) + gamma dt w^n = dt^2 M; a swing, so without a component
      // along n (twisting a segment about itself does not move it).
      Vec3 rot = rate_[i] * (1.0 - gamma * dt * inv_i) + (dt * dt * inv_i) * M;
      rot -= rot.dot(n) * n;
      const double step_angle = rot.norm();
      if (step_angle > params_.max_angle_step) rot *= params_.max_angle_step / step_angle;
      Vec3 next = rotatePerpendicular(rot, n).normalized();
      const Vec3 free_next = next;
      w.free_dir[local] = free_next;
      const bool pivot_moved = pivot != free_pivot;
      free_pivot = free_pivot + d * free_next;
      next = limitBend(rest, next);
      if (!bodies_now.empty() || partner_start_[i + 1] > partner_start_[i]) {
        if (pivot_moved) prepareBodies(w, pivot, d, positions_[i], bodies_now, bodies_before);
        next = resolveCollisions(w, static_cast<int>(i), pivot, d, next, bodies_now, bodies_before);
        countPenetration(w, pivot + d * next, bodies_now, tally);
      }
      // The rotation of this substep: rot itself unless a limit or a constraint moved the end.
      if (next != free_next) rot = rotationVectorBetween(n, next);
      place(i, pivot, d, next, rot);
      checkBand(i);
      parent = i;
    }
  }
  if (outside_band) {
    w.exact_relaxed = true;
    relaxStrip(w, si, bodies_now, bodies_before);
    for (int p = s.columns; p < s.pointCount(); ++p) {
      const std::size_t i = static_cast<std::size_t>(offset + p);
      tally.max_rate = std::max(tally.max_rate, rate_[i].norm() / dt);
      for (const Ellipsoid& e : bodies_now)
        if (e.contains(positions_[i]))
          tally.max_penetration =
              std::max(tally.max_penetration, -e.closestPoint(positions_[i]).signed_distance);
    }
  }
}

void Simulator::countPenetration(const SweepScratch& w, const Vec3& end, const std::vector<Ellipsoid>& now,
                                 StepTally& tally) const {
  bool inside = false;
  for (std::size_t b : w.near)
    if (now[b].contains(end)) {
      tally.max_penetration = std::max(tally.max_penetration, -now[b].closestPoint(end).signed_distance);
      inside = true;
    }
  if (inside) ++tally.penetrations;
}

void Simulator::positionsWorld(const Iso3& head_pose, std::vector<Vec3>& out) const {
  out.resize(positions_.size());
  for (std::size_t i = 0; i < positions_.size(); ++i) out[i] = head_pose * positions_[i];
}

}  // namespace hair_sim
