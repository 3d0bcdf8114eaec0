#include "hair_sim/core/model/HairstyleGenerator.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "hair_sim/core/geometry/Tessellator.hpp"
#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Point of the scalp at polar angle alpha (from the ellipsoid's +z) and azimuth beta (from +x toward +y).
Vec3 scalpPoint(const Ellipsoid& scalp, double alpha, double beta) {
  const Vec3 unit(std::sin(alpha) * std::cos(beta), std::sin(alpha) * std::sin(beta), std::cos(alpha));
  return scalp.center() + scalp.S() * unit;
}

/// Lowest polar angle of the hairline at azimuth beta: the forehead (beta = 0) to the nape (beta = pi).
double hairlineAlpha(double beta) {
  const double front = 62.0 * kPi / 180.0;
  const double back = 112.0 * kPi / 180.0;
  return front + (back - front) * 0.5 * (1.0 - std::cos(beta));
}

/// Moves `end` (at distance d from `pivot`) out of every body, keeping the distance. A few fixed-point
/// iterations of "radially out, then back onto the sphere of radius d around the pivot".
Vec3 drape(const Vec3& pivot, Vec3 end, double d, const std::vector<Ellipsoid>& bodies) {
  for (int iteration = 0; iteration < 30; ++iteration) {
    bool moved = false;
    for (const Ellipsoid& body : bodies) {
      if (body.implicitValue(end) < 1e-9) {
        const Vec3 out = body.radialProjection(end);
        const Vec3 push = out + 1e-4 * body.normalAt(out);
        end = pivot + d * (push - pivot).normalized();
        moved = true;
      }
    }
    if (!moved) break;
  }
  return end;
}

/// The hair length of a draped strip: where its surface, not its control polygon, ends. The spline
/// cuts the corners of a bent chain, so it is shorter than the polygon; the shortest column of a fine
/// tessellation (a hair's breadth less, so that every column is clipped exactly there) makes each
/// tessellated column as long as the strip's hair length at rest.
double splineLength(const Strip& s) {
  Tessellator fine(LevelOfDetail{4, 16});
  StripMesh mesh;
  fine.tessellate(s.points, s.columns, s.rows, 1e3, mesh);
  double shortest = 1e300;
  for (int iu = 0; iu < mesh.n_u; ++iu) {
    double length = 0.0;
    for (int iv = 1; iv < mesh.n_v; ++iv)
      length += (mesh.positions[static_cast<std::size_t>(mesh.index(iu, iv))] -
                 mesh.positions[static_cast<std::size_t>(mesh.index(iu, iv - 1))])
                    .norm();
    shortest = std::min(shortest, length);
  }
  return shortest * (1.0 - 1e-6);
}

/// Each ring's share of the strips: in proportion to its circumference (sin of its mean polar angle).
struct Rings {
  std::vector<double> fraction, weight;
  double weight_sum = 0.0;
  explicit Rings(int rings)
      : fraction(static_cast<std::size_t>(rings)), weight(static_cast<std::size_t>(rings)) {
    for (std::size_t k = 0; k < fraction.size(); ++k) {
      fraction[k] = (static_cast<double>(k) + 0.6) / (rings + 0.1);
      weight[k] = std::sin(fraction[k] * hairlineAlpha(kPi / 2));
      weight_sum += weight[k];
    }
  }
  int count(std::size_t k, int strips) const {
    return std::max(3, static_cast<int>(std::lround(strips * weight[k] / weight_sum)));
  }
};

}  // namespace

int generatedStripCount(const GeneratorOptions& o) {
  if (o.strips < 1 || o.rings < 1)
    throw std::invalid_argument("generatedStripCount(...) : strips " + std::to_string(o.strips) +
                                " and rings " + std::to_string(o.rings) + " must be >= 1");
  const Rings rings(o.rings);
  int n = 0;
  for (std::size_t k = 0; k < rings.weight.size(); ++k) n += rings.count(k, o.strips);
  return n;
}

Hairstyle generateHairstyle(const Ellipsoid& scalp, const GeneratorOptions& o,
                            const std::vector<Ellipsoid>& obstacles) {
  if (o.strips < 1)
    throw std::invalid_argument("generateHairstyle(...) : strips " + std::to_string(o.strips) + " < 1");
  if (o.rings < 1)
    throw std::invalid_argument("generateHairstyle(...) : rings " + std::to_string(o.rings) + " < 1");
  if (o.columns < Strip::kMinColumns)
    throw std::invalid_argument("generateHairstyle(...) : columns " + std::to_string(o.columns) + " < 2");
  if (o.columns > Strip::kMaxColumns)
    throw std::invalid_argument("generateHairstyle(...) : columns " + std::to_string(o.columns) + " > " +
                                std::to_string(Strip::kMaxColumns));
  if (o.rows < Strip::kMinRows)
    throw std::invalid_argument("generateHairstyle(...) : rows " + std::to_string(o.rows) + " < 4");
  if (o.rows > Strip::kMaxRows)
    throw std::invalid_argument("generateHairstyle(...) : rows " + std::to_string(o.rows) + " > " +
                                std::to_string(Strip::kMaxRows));
  if (!(o.length_front > 0.0))
    throw std::invalid_argument("generateHairstyle(...) : length_front " + formatDouble(o.length_front) +
                                " m must be > 0");
  if (!(o.length_back > 0.0))
    throw std::invalid_argument("generateHairstyle(...) : length_back " + formatDouble(o.length_back) +
                                " m must be > 0");

  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);

  // Strips per ring in proportion to the ring's circumference (sin of its mean polar angle).
  const Rings rings(o.rings);
  const std::vector<double>& ring_fraction = rings.fraction;

  Hairstyle style;
  style.scalp = scalp;
  const double mean_radius = scalp.radii().mean();
  for (int k = 0; k < o.rings; ++k) {
    const std::size_t ks = static_cast<std::size_t>(k);
    const int count = rings.count(ks, o.strips);
    // Hair rooted higher lies over the layers below it: lift its drape surface by a gap per layer.
    const double lift = o.thickness_margin * 1.25 + o.layer_gap * (o.rings - 1 - k);
    std::vector<Ellipsoid> bodies;
    bodies.push_back(scalp.inflated(lift));
    for (const Ellipsoid& b : obstacles) bodies.push_back(b.inflated(o.thickness_margin * 1.5));
    const double phase = 0.5 * (k % 2) * 2.0 * kPi / count;
    for (int j = 0; j < count; ++j) {
      const double beta = phase + 2.0 * kPi * j / count;
      const double alpha = ring_fraction[ks] * hairlineAlpha(beta);
      const double spacing = std::sin(alpha) * mean_radius * 2.0 * kPi / count;
      const double width = std::max(0.01, o.width_overlap * spacing);
      const double dbeta = width / std::max(1e-3, std::sin(alpha) * mean_radius);

      Strip s;
      s.name = "r" + std::to_string(k) + "s" + std::to_string(j);
      s.columns = o.columns;
      s.rows = o.rows;
      s.thickness_margin = o.thickness_margin;
      s.width = width;
      const double back = 0.5 * (1.0 - std::cos(beta));  // 0 at the front, 1 at the back
      s.hair_length =
          (o.length_front + (o.length_back - o.length_front) * back) * (1.0 + o.length_jitter * uniform(rng));
      const float shade = static_cast<float>(1.0 + o.color_jitter * uniform(rng));
      s.color = Rgba{std::min(1.f, o.color.r * shade), std::min(1.f, o.color.g * shade),
                     std::min(1.f, o.color.b * shade), o.color.a};
      s.points.resize(static_cast<std::size_t>(s.pointCount()));
      const double d = s.hair_length / (s.rows - 1);
      const double strip_side =
          (scalpPoint(scalp, alpha, beta).y() - scalp.center().y() >= o.parting_y) ? 1.0 : -1.0;
      for (int c = 0; c < s.columns; ++c) {
        const double b = beta + dbeta * (static_cast<double>(c) / (s.columns - 1) - 0.5);
        const Vec3 root = scalpPoint(scalp, alpha, b);
        const Vec3 normal = scalp.normalAt(root);
        s.point(0, c) = root;
        // Flow: down, away from the parting, a little backwards on top; the first segment leaves the scalp.
        const double side = strip_side;  // the whole strip falls to one side of the parting
        const double top = std::max(0.0, (root - scalp.center()).z() / scalp.radii().z());
        Vec3 flow(-0.25 * top, 0.55 * side * top, -1.0);
        flow.normalize();
        Vec3 dir = (0.9 * normal + flow).normalized();
        Vec3 pivot = root;
        for (int r = 1; r < s.rows; ++r) {
          Vec3 end = drape(pivot, pivot + d * dir, d, bodies);
          s.point(r, c) = end;
          const Vec3 taken = (end - pivot).normalized();
          dir = (0.45 * taken + flow).normalized();
          pivot = end;
        }
      }
      s.hair_length = splineLength(s);
      style.strips.push_back(std::move(s));
    }
  }
  return style;
}

Hairstyle generateHairstyle(const SimConfig& config, const Iso3& head_in_world,
                            const GeneratorOptions& options) {
  Ellipsoid scalp(Vec3::Zero(), Mat3::Identity(), Vec3(0.095, 0.075, 0.115));
  std::vector<Ellipsoid> obstacles;
  for (const Body& b : config.bodies) {
    if (b.frame != config.head_frame && b.frame != config.world_frame)
      throw std::invalid_argument("bodies: body '" + b.name + "' is in frame '" + b.frame +
                                  "': the generator knows only head_frame '" + config.head_frame +
                                  "' and world_frame '" + config.world_frame + "'");
    if (b.name == "head")
      scalp = b.shape;
    else
      obstacles.push_back(b.frame == config.head_frame ? b.shape
                                                       : b.shape.transformed(head_in_world.inverse()));
  }
  return generateHairstyle(scalp, options, obstacles);
}

}  // namespace hair_sim
