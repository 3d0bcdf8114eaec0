#include "hair_sim/core/geometry/HairMeshBuilder.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "../LaneWorkers.hpp"
#include "../SimdDispatch.hpp"

namespace hair_sim {

namespace {
/// Bodies whose test the bounding box of a strip's vertices can skip (the others are always tested).
constexpr std::size_t kMaxBoxedBodies = 64;

/// For each group g of four vertices (xyz[12 g ...], three doubles each): bit t of masks[g] is set when one
/// of them may be in reach of body t, that is when its squared distance to centres[t] is not over reach2[t]
/// (NaN included). Branch-free over the vertices, four at a time (GCC's vector extension; AVX2 where the CPU
/// has it, chosen at load time; HairMeshBuilderSimdPathsBitIdentical compares the two).
#if defined(HAIR_SIM_AVX2_DISPATCH)
__attribute__((target_clones("avx2", "default")))
#endif
void reachMasks(const double* xyz, std::size_t groups, const double* centres, const double* reach2,
                std::size_t bodies, std::uint64_t* masks) {
  typedef double V __attribute__((vector_size(32)));
  for (std::size_t g = 0; g < groups; ++g) {
    const double* p = xyz + 12 * g;
    const V x = {p[0], p[3], p[6], p[9]};
    const V y = {p[1], p[4], p[7], p[10]};
    const V z = {p[2], p[5], p[8], p[11]};
    std::uint64_t mask = 0;
    for (std::size_t t = 0; t < bodies; ++t) {
      const V dx = x - centres[3 * t], dy = y - centres[3 * t + 1], dz = z - centres[3 * t + 2];
      const auto out = (dx * dx + dy * dy + dz * dz) > reach2[t];  // false for NaN
      const bool all_out = (out[0] & out[1] & out[2] & out[3]) != 0;
      mask |= static_cast<std::uint64_t>(!all_out) << t;
    }
    masks[g] = mask;
  }
}

/// The bounding box (lo, hi) of `count` >= 1 vertices (xyz, three doubles each), and whether every coordinate
/// is finite (the box is then exact: min and max do not round). Four vertices at a time as reachMasks.
#if defined(HAIR_SIM_AVX2_DISPATCH)
__attribute__((target_clones("avx2", "default")))
#endif
bool boundingBox(const double* xyz, std::size_t count, double lo[3], double hi[3]) {
  typedef double V __attribute__((vector_size(32)));
  for (int r = 0; r < 3; ++r) lo[r] = hi[r] = xyz[r];
  std::size_t k = 0;
  if (count >= 4) {
    // Four vertices are three vectors: [x0 y0 z0 x1] [y1 z1 x2 y2] [z2 x3 y3 z3].
    V low[3], high[3];
    for (int j = 0; j < 3; ++j) {
      V v;
      __builtin_memcpy(&v, xyz + 4 * j, sizeof v);
      low[j] = high[j] = v;
    }
    V non_finite = V{} + 0.0;  // v - v: 0 when finite, NaN otherwise
    for (; k + 4 <= count; k += 4) {
      for (int j = 0; j < 3; ++j) {
        V v;
        __builtin_memcpy(&v, xyz + 3 * k + 4 * j, sizeof v);
        low[j] = v < low[j] ? v : low[j];
        high[j] = v > high[j] ? v : high[j];
        non_finite += v - v;
      }
    }
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 4; ++l) {
        const int r = (4 * j + l) % 3;
        lo[r] = std::min(lo[r], low[j][l]);
        hi[r] = std::max(hi[r], high[j][l]);
      }
    if (!(non_finite[0] == 0.0 && non_finite[1] == 0.0 && non_finite[2] == 0.0 && non_finite[3] == 0.0))
      return false;
  }
  bool finite = true;
  for (; k < count; ++k)
    for (int r = 0; r < 3; ++r) {
      const double v = xyz[3 * k + static_cast<std::size_t>(r)];
      lo[r] = std::min(lo[r], v);
      hi[r] = std::max(hi[r], v);
      finite = finite && v - v == 0.0;
    }
  return finite;
}

LevelOfDetail chooseLevel(const Hairstyle& style, const HairMeshOptions& o) {
  if (o.max_triangles <= 0) return o.level_of_detail;
  return Tessellator::selectLevelOfDetail(HairMeshBuilder::stripShapes(style), o.max_triangles);
}
}  // namespace

std::vector<StripShape> HairMeshBuilder::stripShapes(const Hairstyle& hairstyle) {
  std::vector<StripShape> shapes;
  shapes.reserve(hairstyle.strips.size());
  for (const Strip& s : hairstyle.strips) shapes.push_back(StripShape{s.columns, s.rows});
  return shapes;
}

std::int64_t HairMeshBuilder::minimumTriangles(const Hairstyle& hairstyle) {
  return Tessellator::triangleCount(stripShapes(hairstyle), Tessellator::ladderLevel(0));
}

HairMeshBuilder::HairMeshBuilder(const Hairstyle& hairstyle, const HairMeshOptions& options)
    : hairstyle_(hairstyle), level_of_detail_(chooseLevel(hairstyle, options)), look_(options.look) {
  tessellators_.emplace_back(level_of_detail_, options.method);
  meshes_.resize(hairstyle_.strips.size());
  colours_.resize(hairstyle_.strips.size());
  profiles_.resize(hairstyle_.strips.size());
}

HairMeshBuilder::~HairMeshBuilder() = default;

void HairMeshBuilder::setThreads(int threads) {
  if (threads < 1 || threads > 64)
    throw std::invalid_argument("HairMeshBuilder::setThreads(...) : threads must be in [1, 64], got " +
                                std::to_string(threads));
  workers_.reset();
  if (threads > 1) workers_.reset(new LaneWorkers(threads - 1));
}

int HairMeshBuilder::threads() const { return workers_ ? workers_->helpers() + 1 : 1; }

void HairMeshBuilder::build(const std::vector<Vec3>& points, const std::vector<int>& strip_offsets,
                            const Ellipsoid& scalp, const std::vector<Ellipsoid>& bodies) {
  const std::size_t strips = hairstyle_.strips.size();
  if (strip_offsets.size() != strips)
    throw std::invalid_argument("HairMeshBuilder::build(...) : " + std::to_string(strip_offsets.size()) +
                                " strip offsets for " + std::to_string(strips) + " strips");
  for (std::size_t s = 0; s < strips; ++s) {
    const std::size_t first = static_cast<std::size_t>(strip_offsets[s]);
    const int count = hairstyle_.strips[s].pointCount();
    if (strip_offsets[s] < 0)
      throw std::invalid_argument("HairMeshBuilder::build(...) : strip " + std::to_string(s) + ": offset " +
                                  std::to_string(strip_offsets[s]) + " is negative");
    if (first + static_cast<std::size_t>(count) > points.size())
      throw std::invalid_argument(
          "HairMeshBuilder::build(...) : too few points for strip " + std::to_string(s) + ": its " +
          std::to_string(count) + " points from offset " + std::to_string(first) + " need " +
          std::to_string(first + count) + ", " + std::to_string(points.size()) + " given");
  }
  projected_ = 0;  // (after the checks: a refused build leaves the last one's count with its meshes)
  // A vertex farther from a body's centre than its largest radius (with 1e-9 to spare) is outside it: the
  // exact test (a transform into the body's sphere space) only for the others.
  body_reach2_.clear();
  for (const Ellipsoid& e : bodies) {
    const double reach = e.radii().maxCoeff() * (1.0 + 1e-9);
    body_reach2_.push_back(reach * reach);
  }
  points_ = &points;
  strip_offsets_ = &strip_offsets;
  scalp_ = &scalp;
  bodies_ = &bodies;
  if (!workers_ || strips < static_cast<std::size_t>(kMinStripsForHelpers)) {
    buildStrips(0, strips, tessellators_.front(), projected_);
    return;
  }
  const std::size_t blocks = (strips + kStripsPerBlock - 1) / kStripsPerBlock;
  while (tessellators_.size() < blocks)
    tessellators_.emplace_back(level_of_detail_, tessellators_.front().method());
  block_projected_.assign(blocks, 0);
  block_errors_.assign(blocks, nullptr);
  workers_->start(blocks, &HairMeshBuilder::buildBlock, this);
  workers_->finish();
  for (std::size_t b = 0; b < blocks; ++b) {
    if (block_errors_[b]) std::rethrow_exception(block_errors_[b]);
    projected_ += block_projected_[b];
  }
}

void HairMeshBuilder::buildBlock(void* context, std::size_t block) {
  HairMeshBuilder& self = *static_cast<HairMeshBuilder*>(context);
  const std::size_t first = block * kStripsPerBlock;
  const std::size_t last = std::min(first + kStripsPerBlock, self.hairstyle_.strips.size());
  try {
    self.buildStrips(first, last, self.tessellators_[block], self.block_projected_[block]);
  } catch (...) {  // rethrown on the calling thread
    self.block_errors_[block] = std::current_exception();
  }
}

void HairMeshBuilder::buildStrips(std::size_t first_strip, std::size_t last_strip, Tessellator& tessellator,
                                  int& projected) {
  const std::vector<Vec3>& points = *points_;
  const Ellipsoid& scalp = *scalp_;
  const std::vector<Ellipsoid>& bodies = *bodies_;
  // The strips are tessellated kBatch at a time in one call (four to a kernel, one per SIMD lane, where
  // they have two control columns), then finished one by one while their meshes are in cache.
  constexpr std::size_t kBatch = 4;
  StripInput inputs[kBatch];  // (buildStrips runs on several threads at once: on the stack)
  for (std::size_t s = first_strip; s < last_strip; ++s) {
    if ((s - first_strip) % kBatch == 0) {
      const std::size_t count = std::min(kBatch, last_strip - s);
      for (std::size_t k = 0; k < count; ++k) {
        const Strip& strip = hairstyle_.strips[s + k];
        inputs[k] = {points.data() + (*strip_offsets_)[s + k], strip.columns, strip.rows, strip.hair_length};
      }
      tessellator.tessellate(inputs, count, &meshes_[s], s);
    }
    const Strip& strip = hairstyle_.strips[s];
    StripMesh& mesh = meshes_[s];
    for (int iu = 0; iu < mesh.n_u; ++iu) {
      Vec3& p = mesh.positions[static_cast<std::size_t>(mesh.index(iu, 0))];
      p = scalp.radialProjection(p);
    }
    // Vertices out of the bodies (the root edge excepted). A body whose reach misses the box around the
    // vertices holds none of them: its test is skipped (the box's distance bounds every vertex's, rounding
    // included), unless a projection out of an earlier body has moved the vertex. A non-finite vertex (the
    // box would leave it out) has every body tested, as without the box.
    const std::size_t first_tested = static_cast<std::size_t>(mesh.n_u);
    Vec3 box_lo, box_hi;
    const bool finite = boundingBox(mesh.positions[first_tested].data(), mesh.positions.size() - first_tested,
                                    box_lo.data(), box_hi.data());
    bool near[kMaxBoxedBodies];
    const std::size_t boxed = finite ? std::min(bodies.size(), kMaxBoxedBodies) : 0;
    for (std::size_t b = 0; b < boxed; ++b) {
      const Vec3& c = bodies[b].center();
      const Vec3 gap = (box_lo - c).cwiseMax(c - box_hi).cwiseMax(0.0);  // per axis: 0 when c is within
      near[b] = !(gap.squaredNorm() > body_reach2_[b]);                  // as the vertex's test below
    }
    // The bodies each vertex is tested against first (the others only after a projection).
    std::size_t tested[kMaxBoxedBodies];
    std::size_t tested_count = 0;
    for (std::size_t b = 0; b < std::min(bodies.size(), kMaxBoxedBodies); ++b)
      if (b >= boxed || near[b]) tested[tested_count++] = b;
    const bool all_tested = bodies.size() > kMaxBoxedBodies;  // the bodies past kMaxBoxedBodies: always
    auto exact = [&](std::size_t k) {
      Vec3& p = mesh.positions[k];
      bool moved = false;
      for (std::size_t b = 0; b < bodies.size(); ++b) {
        if (b < boxed && !near[b] && !moved) continue;
        const Ellipsoid& e = bodies[b];
        if ((p - e.center()).squaredNorm() > body_reach2_[b] || e.implicitValue(p) >= 0.0) continue;
        const Ellipsoid::ClosestPoint cp = e.closestPoint(p);
        p = cp.point + 1e-6 * cp.normal;
        moved = true;
        ++projected;
      }
    };
    // Four vertices at a time, the test above with a margin over its rounding (1e-9 relative) and without a
    // branch per vertex: a body none of the four is in reach of is passed; for the others, where none of
    // the four can be inside (the common case), the exact loop above would leave them all unmoved, so it is
    // skipped; otherwise (a NaN included) it runs. The same results (HairMeshBuilderSimdPathsBitIdentical,
    // the shipped scenarios' PLY frames); with boundingBox, the node's mesh 0.71 x.
    std::size_t k = first_tested;
    const std::size_t count = mesh.positions.size();
    if (!all_tested && tested_count == 0) k = count;  // no body can act: every vertex stays
    // (buildStrips runs on several threads at once: its buffers are on the stack.)
    double centres[3 * kMaxBoxedBodies];
    double reach2[kMaxBoxedBodies];
    for (std::size_t t = 0; t < tested_count; ++t) {
      const Vec3& c = bodies[tested[t]].center();
      for (int r = 0; r < 3; ++r) centres[3 * t + static_cast<std::size_t>(r)] = c[r];
      reach2[t] = body_reach2_[tested[t]] * (1.0 + 1e-9);
    }
    constexpr std::size_t kChunk = 64;  // groups of four vertices per call
    std::uint64_t masks[kChunk];
    while (!all_tested && k + 4 <= count) {
      const std::size_t groups = std::min(kChunk, (count - k) / 4);
      reachMasks(mesh.positions[k].data(), groups, centres, reach2, tested_count, masks);
      for (std::size_t g = 0; g < groups; ++g, k += 4) {
        std::uint64_t in_reach = masks[g];  // most groups: no body in reach
        if (in_reach == 0) continue;
        const Vec3* q = &mesh.positions[k];
        bool may_act = false;
        for (; in_reach != 0 && !may_act; in_reach &= in_reach - 1) {
          const std::size_t t = static_cast<std::size_t>(__builtin_ctzll(in_reach));
          const Ellipsoid& e = bodies[tested[t]];
          for (int l = 0; l < 4; ++l) {  // f = |q|^2 - 1 in sphere space; the margin scales with |q|^2
            const double f = e.implicitValue(q[l]);
            may_act |= !(f > 1e-9 * (2.0 + f));  // (out of reach but inside: tested anyway)
          }
        }
        if (may_act)
          for (int l = 0; l < 4; ++l) exact(k + static_cast<std::size_t>(l));
      }
    }
    for (; k < count; ++k) exact(k);
    std::vector<double>& profiles = profiles_[s];  // the stripes depend on the seed and n_u only
    if (profiles.size() != static_cast<std::size_t>(mesh.n_u))
      look_.stripeProfiles(mesh, static_cast<std::uint32_t>(s * 2654435761u), profiles);
    look_.colorize(mesh, strip.color, profiles, colours_[s]);
  }
}

std::int64_t HairMeshBuilder::triangleCount() const {
  std::int64_t n = 0;
  for (const StripMesh& m : meshes_) n += m.triangleCount();
  return n;
}

int HairMeshBuilder::vertexCount() const {
  int n = 0;
  for (const StripMesh& m : meshes_) n += m.vertexCount();
  return n;
}

double HairMeshBuilder::maxPenetration(const std::vector<Ellipsoid>& bodies) const {
  double worst = 0.0;
  for (const StripMesh& m : meshes_)
    for (const Vec3& p : m.positions)
      for (const Ellipsoid& e : bodies)
        if (e.implicitValue(p) < -1e-12) worst = std::max(worst, -e.closestPoint(p).signed_distance);
  return worst;
}

}  // namespace hair_sim
