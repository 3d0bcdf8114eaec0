#pragma once
/// Procedural hairstyle: covers the upper scalp with strips in rings (layers), with a parting on
/// top, longer hair at the back than at the front, lengths varied by a seeded generator, and each
/// strip draped over the scalp (and over the given obstacles) so that the styled shape starts clear of
/// every body inflated by the thickness margin.
#include <cstdint>
#include <vector>

#include "hair_sim/core/model/Hairstyle.hpp"
#include "hair_sim/core/model/SimConfig.hpp"

namespace hair_sim {

struct GeneratorOptions {
  int strips = 100;                 ///< approximate number of strips (the rings round it)
  int rings = 5;                    ///< layers from the crown down to the ears/nape
  int columns = 2;                  ///< control points across a strip
  int rows = 5;                     ///< control points along a strip
  double length_front = 0.12;       ///< hair length at the fringe (m)
  double length_back = 0.30;        ///< hair length at the nape (m)
  double length_jitter = 0.08;      ///< relative random length variation (+-)
  double parting_y = 0.015;         ///< parting line offset to the left (+y), head frame (m)
  double width_overlap = 1.35;      ///< strip width relative to the spacing of roots on its ring
  double thickness_margin = 0.004;  ///< per-strip margin (m)
  double layer_gap = 0.004;         ///< extra lift per layer above the ones rooted below (m)
  Rgba color{0.28f, 0.17f, 0.09f, 1.0f};
  double color_jitter = 0.08;  ///< relative random brightness variation
  std::uint32_t seed = 7;
};

/// The number of strips generateHairstyle makes for these options (every ring has at least 3, so it can be
/// more than options.strips). Needs strips and rings >= 1.
int generatedStripCount(const GeneratorOptions& options);

/// Obstacles are bodies at the rest pose expressed in the head frame (the scalp need not be listed).
Hairstyle generateHairstyle(const Ellipsoid& scalp, const GeneratorOptions& options,
                            const std::vector<Ellipsoid>& obstacles = {});

/// The same, draped over a config's bodies with the head frame at `head_in_world` (the rest pose):
/// the body named "head" is the scalp, bodies in head_frame stay as they are, the others (in
/// world_frame) are brought into the head frame; a body in any other frame is an error (as in the
/// offline runner). Without a "head" body the scalp is an adult head
/// of radii 0.095 x 0.075 x 0.115 m at the head frame's origin.
Hairstyle generateHairstyle(const SimConfig& config, const Iso3& head_in_world,
                            const GeneratorOptions& options);

}  // namespace hair_sim
