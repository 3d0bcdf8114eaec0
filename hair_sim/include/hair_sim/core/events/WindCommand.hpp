#pragma once
/// The wind commanded to hair_sim_node (hair_sim_msgs/Wind): a mean air velocity and a turbulence relative
/// to the mean speed, each blended linearly from what the previous command gave to the new values over the
/// command's ramp time, from its start. Sampled by time only (a replay gives the same wind).
#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

class WindCommand {
 public:
  /// A new command from `start` (s): the mean velocity (m/s) and the relative turbulence blend from what the
  /// commands so far give at `start` (their means, without the fluctuation) to `velocity` and `turbulence`
  /// over `ramp` s (0 = at once).
  void set(double start, const Vec3& velocity, double turbulence, double ramp);
  /// Ends any ramp: the last command's values hold at every time (time went backwards).
  void settle();
  /// The blend's weight of the newest command at t: 0 before its start, 1 after its ramp.
  double weight(double t) const;
  /// Mean air velocity at t (m/s), without the fluctuation.
  Vec3 mean(double t) const;
  /// Relative turbulence at t.
  double turbulence(double t) const;
  /// Air velocity at t (m/s): the mean plus a smooth, deterministic fluctuation (incommensurate sines per
  /// axis) of about turbulence(t) x |mean(t)| per component.
  Vec3 at(double t) const;

 private:
  Vec3 from_ = Vec3::Zero(), to_ = Vec3::Zero();
  double turbulence_from_ = 0.0, turbulence_to_ = 0.0;
  double start_ = 0.0, ramp_ = 0.0;
};

}  // namespace hair_sim
