#pragma once
/// The substep loop (paper 4.1): every column of control points of every strip is a chain of rigid
/// segments (Fig. 2c) solved from the root down with the angular dynamics (1)-(7).
///
/// Angles. The paper's theta and phi are polar angles; here each segment's two angles are measured
/// about the two axes perpendicular to the segment in a frame that travels with it, so the working
/// point is always at the origin of its own chart and no orientation reaches a pole. Equation (7)
/// (corrected, see DESIGN.md) then reads, with w^n the rotation vector from the direction at step
/// n-1 to the one at step n:
///     I (w^{n+1} - w^n) + gamma dt w^n = dt^2 M,   M = M_spring + M_external     (2)
///     M_external = (d/2) n x F                       (4),(5): u F_theta, v F_phi with u = d/2
///     M_spring   = -k (angle from the rest direction) about the axis rest x n     (3)
///     F          = rho d (g + a) + d f               (6), a fictitious, f = air_drag (v_air - v_hair)
///     I          = rho d^3 / 3
/// The rest direction of a segment is its styled direction carried by the rotation of its parent
/// (relative to the parent segment, the hinge); the first segment's is fixed in the head frame.
/// Rest directions are compensated so that the styled shape is the equilibrium under gravity at the
/// rest head pose.
///
/// Collisions (paper 4.3a): a control point inside a body inflated by its strip's thickness margin
/// gets the reaction constraint (8)-(10) on F. After the angle update, the new end point of every
/// segment is checked against every inflated body: inside, on a path that entered the body during
/// the substep (the paper's ray test, in sphere space, with the body's motion), or with the segment
/// cutting through it, the segment is turned (length kept) toward the outward normal at its pivot, to
/// the nearest direction where none of that holds (a bracket on the arc narrowed by the ITP method, every
/// probe decided by the tests themselves). So no control point below the roots ends a substep inside an
/// inflated body.
///
/// Springs (paper 4.3b, equation 11): pairs within a strip (neighbouring columns, same row) and
/// between strips (control points closer than a radius at rest, found through a uniform grid, the
/// nearest few per point) pull or push along the pair with k_s times the stretch outside the band
/// [proximity_factor, far_factor] x rest length; their force joins F before the projection (5).
/// A hard band [contact, far_factor] x rest length, contact = contact_fraction x proximity_factor (the
/// repulsion acts first, the constraint is its backstop), is also kept as a constraint on each new end
/// point (bodies take precedence): the later point of each pair in the sweep meets it on the circle of its
/// reachable end points, and a strip whose width still leaves the band gets Gauss-Seidel passes in which
/// every pair is kept from both ends, then joint placements of whole rows (see relaxStrip), so strips never
/// come closer than contact x rest length nor spread wider than far_factor x it, unless the bodies (which
/// keep the last word) forbid every placement: in one simulated hour of the soak, 4 substeps, all under a
/// nod of pi/2 at 20 Hz.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/dynamics/HeadState.hpp"
#include "hair_sim/core/events/EventSchedule.hpp"
#include "hair_sim/core/model/Body.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"
#include "hair_sim/core/model/PhysicsParameters.hpp"

namespace hair_sim {

class LaneWorkers;

namespace lanes {
/// Internal to step()'s vectorised path: one body inflated by a strip's margin, in the head frame, now and
/// at the previous substep, as flat arrays. Each value is stored once per lane of a block (4), so that the
/// lanes kernel reads it as a whole vector, an operand in memory, instead of broadcasting it each time.
struct LaneBody {
  static constexpr int kCopies = 4;  ///< lanes::kLanes
  double centre[3][kCopies];
  double sinv[9][kCopies];  ///< S^-1, row-major
  double centre_before[3][kCopies];
  double sinv_before[9][kCopies];
  double bound_radius[kCopies];  ///< ball about the centre that holds the body (see Simulator::BodyBound)
  double shift[kCopies];
  // Of the body's motion (Simulator::BodyBound), for the quick reject: 1 + motion, (1 - motion)^2, and
  // whether motion < 0.5 (-1 or 0).
  double grow[kCopies];
  double keep2[kCopies];
  long slow[kCopies];
};
}  // namespace lanes

/// Everything the world contributes to one substep.
struct StepInputs {
  HeadState head;
  Vec3 wind = Vec3::Zero();  ///< air velocity, world frame (m/s)
  /// Turbulence added to `wind` at each segment's midpoint (world frame), or none.
  const WindField* turbulence = nullptr;
  /// Gravitational acceleration (world frame, m/s^2) for this substep; none = parameters().gravity.
  /// (The rest compensation stays the one for parameters().gravity.)
  const Vec3* gravity = nullptr;
  /// World pose of each body's frame, in the order of the bodies given to the Simulator.
  std::vector<Iso3> body_frames;
};

/// One spring of equation (11) between control points a and b (indices into positionsHead()).
struct SpringPair {
  int a = 0;
  int b = 0;
  double rest = 0.0;  ///< rest length (m)
  bool within_strip = true;
};

/// Internal to the core: the extremes of the spring pairs' lengths that computeSpringForces publishes
/// (squared ratios to the rest length within and between strips, the smallest squared gap between strips).
struct SpringExtremes {
  double min_within = 1e300, max_within = 0.0, min_between = 1e300, max_between = 0.0, min_gap2 = 1e300;
};

class Simulator {
 public:
  /// How step() advances the chains. Lanes (default): blocks of chains advanced together by loops the
  /// compiler vectorises (AVX-512VL or AVX2 when the CPU has it), and the exact per-strip step for the strips
  /// that need it (a body within reach of a segment's new place, a reaction constraint, a bend over the
  /// limit, a spring pair outside its band). LanesBaseline: the same without AVX2 (bit-identical to Lanes).
  /// LanesAvx2: the same with at most AVX2 (bit-identical to Lanes; for tests on CPUs with AVX-512). Exact:
  /// the per-strip step for every strip (the reference the tests compare the lanes with).
  enum class StepPath { Lanes, LanesBaseline, Exact, LanesAvx2 };

  /// Throws std::invalid_argument on invalid parameters or hairstyle.
  Simulator(Hairstyle hairstyle, PhysicsParameters parameters, std::vector<Body> bodies = {});
  ~Simulator();
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;

  /// Back to the styled rest shape, still.
  void reset();
  /// Puts the hair in the given shape (head frame, positionsHead() order), at rest. Segment lengths
  /// are kept: each segment takes the direction toward its given end point. Roots stay on the scalp.
  /// Throws std::invalid_argument on a wrong size or a non-finite point.
  void setShape(const std::vector<Vec3>& positions_head);
  /// One substep of parameters().substep seconds with the given inputs at its end time. Throws
  /// std::invalid_argument, naming the input and taking no substep, when the head state, the wind, the
  /// gravity or a body frame is not finite, or when body_frames does not match the bodies.
  void step(const StepInputs& inputs);
  /// Swaps the physical parameters between two substeps, keeping the state (shape and rates): the
  /// next step() runs with them. Inertia floors and compensated rest directions are recomputed, and
  /// the spring pairs too when their pairing keys (within/between, radius, max_pairs) changed.
  /// Throws std::invalid_argument (and keeps the old parameters) on an invalid set or on a different
  /// substep, which needs a new Simulator.
  void setParameters(const PhysicsParameters& parameters);

  void setStepPath(StepPath path) { step_path_ = path; }
  StepPath stepPath() const { return step_path_; }
  /// The instruction set the lanes kernel of `path` runs with on this CPU: "AVX-512VL", "AVX2" or "x86-64"
  /// (the baseline; "baseline" on other architectures); "none" for the Exact path. (Benchmarks name it: the
  /// same code is slower without AVX-512.)
  static const char* kernelInstructionSet(StepPath path);
  /// Threads for step() (1 = the calling thread only, the default): on the Lanes paths a helper thread sweeps
  /// the second group of strips (sweepGroupOf) while the calling thread sweeps the first, each with its
  /// blocks of chains and its exact steps, the runs of blocks shared out between the two; then the calling
  /// thread sweeps the boundary. The sweep order is the same with any count, so the hair is bit-identical
  /// with any count; more than 2 threads do not speed the step. Hairstyles of fewer than 512 chains
  /// (kMinBlocksForHelpers blocks) keep the sweeps on the calling thread. Throws std::invalid_argument
  /// outside [1, 64].
  void setThreads(int threads);
  int threads() const;
  /// The sweep group of strip s (every path sweeps the strips in this order, strip order within a group):
  /// 0 the strips whose chains all lie in the first half of the blocks and that share no spring pair with
  /// a strip of the second half, 1 likewise for the second half, 2 the rest (the boundary), swept after both.
  /// Groups 0 and 1 share no spring pair, so they are swept at once on 2 threads.
  /// Throws std::out_of_range for a strip the hairstyle does not have.
  int sweepGroupOf(std::size_t strip) const {
    if (strip >= strip_rank_.size())
      throw std::out_of_range("Simulator::sweepGroupOf(...) : strip " + std::to_string(strip) +
                              ", the hairstyle has " + std::to_string(strip_rank_.size()));
    const std::size_t rank = static_cast<std::size_t>(strip_rank_[strip]);
    return rank < sweep_group_end_[0] ? 0 : rank < sweep_group_end_[1] ? 1 : 2;
  }
  /// Strips the last step() gave to the exact per-strip step (all of them on the Exact path).
  int exactStripCount() const { return exact_strips_; }
  /// Whether the last step() took the springs' forces (11) and the spring ratios from the sweeps of the step
  /// before it (a Lanes path, nothing having moved the hair since: no reset, setShape or setParameters, and
  /// that step did not throw) instead of computing them from the points. Both ways give the same bits; this
  /// says which one ran (false with no springs).
  bool springForcesFromSweeps() const { return springs_from_sweeps_; }

  const Hairstyle& hairstyle() const { return hairstyle_; }
  const PhysicsParameters& parameters() const { return params_; }
  long stepCount() const { return steps_; }
  int controlPointCount() const { return static_cast<int>(positions_.size()); }
  /// All control points, head frame, strip by strip, each row-major (the hairstyle's order). The Lanes paths
  /// swap the state with their buffers in step(): take the reference (or data()) again after a step.
  const std::vector<Vec3>& positionsHead() const { return positions_; }
  /// After a teleport of the head: the bodies' previous poses no longer count (no swept test across the
  /// jump); the hair, kept in the head frame, goes with the head rigidly.
  void forgetBodyMotion() { have_bodies_before_ = false; }
  /// First index of each strip in positionsHead().
  const std::vector<int>& stripOffsets() const { return strip_offset_; }
  /// Control points in the world frame for the given head pose.
  void positionsWorld(const Iso3& head_pose, std::vector<Vec3>& out) const;
  /// Effective moment of inertia used for the segment ending at point k (>= rho d^3/3; see inertiaFloor).
  double inertia(int k) const { return 1.0 / inv_inertia_[static_cast<std::size_t>(k)]; }
  /// Largest angular rate any segment had relative to the head in the last substep (rad/s).
  double maxSegmentRate() const { return max_rate_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  const std::vector<SpringPair>& springs() const { return springs_; }
  /// Deepest control point (below the roots) inside any inflated body after the last substep (m, 0 = none).
  double maxPenetration() const { return max_penetration_; }
  /// Smallest distance between paired control points of different strips (m), measured when the
  /// last substep began (so: the state the substep before it left).
  double minStripGap() const { return min_gap_; }
  /// Smallest distance / rest length over the springs of the given kind, measured as minStripGap().
  double minSpringRatio(bool within_strip) const { return min_ratio_[within_strip ? 1 : 0]; }
  /// Largest distance / rest length over the springs of the given kind, measured as minStripGap().
  double maxSpringRatio(bool within_strip) const { return max_ratio_[within_strip ? 1 : 0]; }
  /// Control points (below the roots) inside an inflated body after the last substep (0 by construction
  /// unless a body is too thin or too fast for the escape search).
  int penetrationCount() const { return penetrations_; }
  /// Segments turned out of a body in the last substep.
  int collisionCount() const { return collisions_; }
  /// The bodies in the head frame, inflated by `margin`, for a head pose and body frame poses.
  std::vector<Ellipsoid> bodiesInHeadFrame(const Iso3& head_pose, const std::vector<Iso3>& body_frames,
                                           double margin) const;

  /// Smallest moment of inertia that keeps the explicit scheme (7) stable with margin for this
  /// angular stiffness and damping: gamma dt / I <= 1 and k dt^2 / I <= 0.5 (omega dt <= 0.71).
  /// Linear springs k_lin acting at the lever d/2 add k_lin (d/2)^2 to the angular stiffness.
  static double inertiaFloor(double stiffness, double damping, double dt);

 private:
  struct SweepScratch;  // (below: the exact step's working state, one per concurrent sweep)
  struct BodyBound;
  struct BandPair;
  void buildChains();
  /// The blocks of chains for the Lanes path (after buildChains).
  void buildLanes();
  /// Constants of one substep shared by the paths (head frame).
  struct StepFrame {
    double dt, rho, k, gamma, drag, cos_max_bend, k_c, c_c;
    Mat3 Rt;
    /// The force (6) on a segment per metre of its length, linear in its midpoint m and the midpoint's
    /// velocity v (head frame): F / d = force0 + force_mid m + force_vel v (+ drag x turbulence), with
    /// force0 = rho (g - a0) + drag air0, force_mid = -rho ([alpha]x + [omega]x^2) - drag [omega]x and
    /// force_vel = -2 rho [omega]x - drag I: gravity, the head frame's linear, angular, centrifugal and
    /// Coriolis accelerations, and the drag of the air (air0 at the head origin) relative to the hair.
    Vec3 force0;
    Mat3 force_mid, force_vel;
    bool turbulent;
  };
  /// What a substep measured.
  struct StepTally {
    double max_rate = 0.0;   ///< rad/s
    double max_rate2 = 0.0;  ///< largest |w|^2 (rad^2)
    double max_penetration = 0.0;
    int penetrations = 0;
  };
  /// The exact step of one strip (offset: its first point): the sweep over its columns, resolveCollisions
  /// for every segment, relaxStrip when its band does not hold. The places of the sweep before `from`
  /// (column * rows + row) take the lanes' results (new_*_), the others the exact step. Every free step is
  /// taken from the parent's free step (its free end, its free direction carrying the rest direction), the
  /// constraints from the parent's final end. With from_lanes (the lanes ran for the strip), a place after
  /// `from` starts from the lanes' free step unless its lane_flag_ says kPointFull or a place above in its
  /// column took the exact step's own dynamics: the bend limit applied when the lanes flagged it
  /// (kPointBend), then committed as it is when no pivot above moved, no body is in the way and no spring
  /// band would move it, else resolveCollisions from it. Lists the points it
  /// places itself in w.exact_placed and sets w.exact_relaxed when relaxStrip ran (stepLanes copies those
  /// back).
  void stepStrip(SweepScratch& w, const StepInputs& in, const StepFrame& f, std::size_t si, int offset,
                 StepTally& tally, int from = 0, bool from_lanes = false);
  /// The penetration tally of a segment's end after resolveCollisions (the bodies w.near of its pivot).
  void countPenetration(const SweepScratch& w, const Vec3& end, const std::vector<Ellipsoid>& now,
                        StepTally& tally) const;
  /// The Lanes path: every block through lanes::stepBlock, the band of every spring pair checked at the new
  /// places, the strips that passed committed, the others through stepStrip, in the sweep order
  /// (buildSweepOrder): the two groups at once on 2 threads or more, then the boundary. The sweeps also scan
  /// the spring pairs at their final lengths and add their forces (11) for the next substep (spring_force_,
  /// the scratch's extremes); at the end spring_scan_sweep_ = sweep_.
  void stepLanes(const StepInputs& in, const StepFrame& f);
  /// lane_constants_ from the segment constants (buildLanes, setParameters).
  void fillLaneConstants();
  /// Point i takes the lanes' result (new_*_) as its state at the end of the substep (the exact step of its
  /// strip); returns |w|^2.
  double commitLanes(std::size_t i);
  /// During a substep: the place at the end of it of partner q (partner_index_[q]) when it already has one,
  /// else null: new_position_ in a strip committed from the lanes (stepLanes' buffer swap makes it the state
  /// at the end), positions_ where the exact step placed it. The partner's strip is read from partner_strip_,
  /// indexed by q like partner_index_ (in order, where strip_of_point_[j] is read at scattered j), and
  /// moved_in_step_ only outside a committed strip. A partner in a strip after the one stepStrip steps in the
  /// sweep order (w.sweep_rank; partner_rank_ read in order too) has no place yet: null without the loads at
  /// j.
  const Vec3* placedPartner(const SweepScratch& w, std::size_t q) const {
    if (partner_rank_[q] > w.sweep_rank) return nullptr;
    const int strip = partner_strip_[q];
    const std::size_t j = static_cast<std::size_t>(partner_index_[q]);
    if (strip_committed_[static_cast<std::size_t>(strip)] == sweep_) return &new_position_[j];
    return moved_in_step_[j] == sweep_ ? &positions_[j] : nullptr;
  }
  /// The lanes' buffers (new_*_) equal to the state (reset: the roots, which no substep writes, must be the
  /// same in both when stepLanes swaps them).
  void syncLaneBuffers();
  /// Inertia floors (1 / I) and compensated rest directions from the lengths, styled directions and params_.
  void updateSegmentConstants();
  void buildSprings();
  /// The sweep order (sweep_order_, strip_rank_, partner_rank_, sweep_group_end_, sweep_mid_block_) from the
  /// blocks and the spring pairs (start of buildBandPairs): the strips whose chains all lie in the first half
  /// of the blocks and that pair with no strip of the second half, then likewise those of the second half,
  /// then the rest (the boundary).
  void buildSweepOrder();
  /// band_pairs_ from springs_, the sweep order and the band's factors (end of buildSprings, setParameters).
  void buildBandPairs();
  /// The springs of the substep: (11) into spring_force_ and the extremes of the pairs' lengths
  /// (min_ratio_, max_ratio_, min_gap_), from stepLanes' sweeps when they found them, else from the points.
  void computeSpringForces();
  /// A band pair's |later - earlier|^2 at the places pos.
  static double bandDist2(const Vec3* pos, const BandPair& bp);
  /// Strip si's band pairs at their lengths dist2[q - band_pair_start_[si]] between the points at pos: the
  /// strip's spring forces cleared, the pairs into the extremes e, then (11) for those outside their dead
  /// band added to spring_force_ (`outside`: room for the strip's pairs). stepLanes' sweeps call it as each
  /// strip is final, computeSpringForces strip by strip in the sweep order: each point's forces are summed
  /// in the same order either way.
  void finishStripSprings(std::size_t si, const double* dist2, const Vec3* pos, SpringExtremes& e,
                          int* outside);
  /// The same for the pairs with a root (root_springs_), after every strip.
  void finishRootSprings(const Vec3* pos, SpringExtremes& e);
  /// The valid direction nearest to dir on the arc toward an escape direction (the ITP method on testMargin,
  /// each probe decided by clearOf's tests, prepareBodies first) for the bodies.
  Vec3 escapeBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& dir,
                    const std::vector<Ellipsoid>& now, bool have_before) const;
  /// Maps the pivot and the previous end of a segment into the sphere space of every body and keeps
  /// the bodies within its reach (w.near); resolveCollisions and the reaction constraint use them.
  void prepareBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& previous_end,
                     const std::vector<Ellipsoid>& now, const std::vector<Ellipsoid>& before);
  /// Turns the segment pivot -> pivot + d * dir out of the bodies (prepareBodies first); returns the
  /// corrected direction.
  Vec3 resolveCollisions(SweepScratch& w, int point, const Vec3& pivot, double d, const Vec3& dir,
                         const std::vector<Ellipsoid>& now, const std::vector<Ellipsoid>& before);
  /// Is the segment pivot -> pivot + d * u clear of near body b (prepareBodies first): end outside, the
  /// segment not cutting through it, the end's path over the substep not entering it?
  bool clearOf(const SweepScratch& w, std::size_t b, double d, const Vec3& u,
               const std::vector<Ellipsoid>& now, bool have_before) const;
  /// The end of direction u in near body b's sphere space (prepareBodies first).
  Vec3 endInSphere(const SweepScratch& w, std::size_t b, double d, const Vec3& u,
                   const std::vector<Ellipsoid>& now) const;
  /// clearOf's tests for near body b on the end q_end (endInSphere): -1 when it passes them all, else the
  /// first it fails: 0 the end inside, 1 the segment through the body, 2 the end's path into it.
  int failedKind(const SweepScratch& w, std::size_t b, const Vec3& q_end, bool have_before) const;
  /// The margin of test `kind` of body b for the end q_end: positive where it passes (up to rounding at its
  /// boundary), smooth and of the first order in the direction at the boundary, for escapeBodies to
  /// interpolate.
  double testMargin(const SweepScratch& w, std::size_t b, int kind, const Vec3& q_end) const;
  /// One probe of escapeBodies: the first of clearOf's tests over w.near that the direction fails (kind -1:
  /// clear, as clearOfAll), and the margin of the test it follows.
  struct EscapeProbe {
    std::size_t body = 0;
    int kind = -1;
    double margin = std::numeric_limits<double>::quiet_NaN();
  };
  /// Maps u into each near body's sphere space once for both.
  EscapeProbe probeEscape(const SweepScratch& w, double d, const Vec3& u, const std::vector<Ellipsoid>& now,
                          bool have_before, std::size_t follow_body = 0, int follow_kind = -1) const;
  /// clearOf for every near body.
  bool clearOfAll(const SweepScratch& w, double d, const Vec3& u, const std::vector<Ellipsoid>& now,
                  bool have_before) const;
  /// The bodies' part of resolveCollisions (prepareBodies first): dir when the segment is clear of every
  /// near body, else the nearest clear direction found by escapeBodies, with the swept test and then the
  /// segment test dropped when no direction passes them all (the end outside every body comes first).
  /// first_level 1 starts without the swept test.
  Vec3 clearBodies(SweepScratch& w, const Vec3& pivot, double d, const Vec3& dir,
                   const std::vector<Ellipsoid>& now, bool have_before, int first_level = 0);
  /// Is some within-strip pair of the strip outside the hard band [contact, far] x rest length?
  bool stripOutsideBand(const SweepScratch& w, std::size_t strip) const;
  /// The same for the pairs of one row of the strip.
  bool rowOutsideBand(const SweepScratch& w, std::size_t strip, int row) const;
  /// Where the row's within-strip pairs are against the band: 0 within, 1 some too far apart, -1 some too
  /// close, 2 both.
  int rowBandSide(const SweepScratch& w, std::size_t strip, int row) const;
  /// A within-strip pair at distance dist against the band: 1 farther than far_factor x far_rest (the far
  /// edge, to 1e-10 relative), -1 closer than the contact edge x rest, else 0.
  int bandSide(double dist, double rest, double far_rest) const;
  /// The hard band's near edge, x rest length: spring_contact_fraction x spring_proximity_factor.
  double contactFactor() const { return params_.spring_contact_fraction * params_.spring_proximity_factor; }
  /// resolveCollisions' band projection for a partner at distance dist (signed_rest as partner_rest_): the
  /// distance to move the end to (just inside the near edge, or the far edge of a within-strip pair), or 0
  /// when the pair is within its band.
  double bandTarget(double dist, double signed_rest) const;
  /// Rest length of the within-strip pair (i, j), or fallback when they are not paired.
  double withinRest(std::size_t i, std::size_t j, double fallback) const;
  /// Gauss-Seidel passes over a strip whose band does not hold after the sweep: every segment again
  /// through resolveCollisions from its (possibly moved) pivot, now with every partner in the strip
  /// already moved, so that each pair is kept from both ends. Then rates and velocities are
  /// recomputed from the state at the start of the substep (start_*_). Rows the passes leave outside
  /// the band (columns crossed, or a tip held by a body, so that no single end can meet it) get parallel
  /// segments turned toward or away from each other, each cleared of the bodies, until the row meets it;
  /// if none does, the row above is held to this row's far edge and both are placed again. Every row is
  /// cleared of the bodies from its (possibly moved) pivots.
  void relaxStrip(SweepScratch& w, std::size_t strip, const std::vector<Ellipsoid>& now,
                  const std::vector<Ellipsoid>& before);

  Hairstyle hairstyle_;
  PhysicsParameters params_;
  long steps_ = 0;
  /// Sweeps begun (each step(); never reset): the mark of moved_in_step_ and strip_committed_.
  long sweep_ = 0;
  double max_rate_ = 0.0;
  std::vector<int> strip_offset_;
  // Per control point k (the segment that ends at k for rows >= 1), head frame.
  // (The segment's midpoint at the end of the last substep, which the next substep's velocity starts from, is
  // not stored: it is the parent's position + d/2 direction, bit for bit, as every path computes it.)
  std::vector<Vec3> positions_;
  std::vector<Vec3> velocity_;       ///< midpoint velocity relative to the head over the last substep
  std::vector<Vec3> direction_;      ///< unit segment direction n
  std::vector<Vec3> rate_;           ///< w: rotation vector of the last substep (rad)
  std::vector<Vec3> styled_dir_;     ///< styled direction (head frame)
  std::vector<Vec3> rest_dir_;       ///< compensated rest direction at the styled pose (head frame)
  std::vector<double> length_;       ///< d
  std::vector<double> inv_inertia_;  ///< 1 / I
  /// Equation (11): the force on each control point this substep; once a strip is swept, the next substep's
  /// (stepLanes adds them in place as it finds the pairs' final lengths).
  std::vector<Vec3> spring_force_;
  std::vector<int> strip_of_point_;
  std::vector<int> margin_of_strip_;  ///< index into margins_
  std::vector<double> margins_;       ///< distinct thickness margins
  std::vector<Body> bodies_;
  std::vector<SpringPair> springs_;
  std::vector<double> spring_inv_rest2_;  ///< per spring pair, 1 / rest^2
  std::vector<int> root_springs_;         ///< the spring pairs with a root (no band pair)
  /// The sweep (sweep_) whose stepLanes scanned every spring pair at its final length (the extremes in the
  /// sweeps' scratch, the forces in spring_force_), which the next computeSpringForces takes instead of its
  /// own scan while nothing else has moved the hair (reset, setShape, buildBandPairs: -1). Set only once
  /// stepLanes has swept every strip: after a step() that threw, the next computeSpringForces computes the
  /// forces afresh, whatever the sweeps left in spring_force_.
  long spring_scan_sweep_ = -1;
  bool springs_from_sweeps_ = false;  ///< springForcesFromSweeps()
  // The sweep (sweep_) in which stepStrip gave a point its final position (the points of a strip committed
  // from the lanes are marked by strip_committed_ instead).
  std::vector<long> moved_in_step_;
  std::vector<int> partner_start_;  ///< CSR: partners of point k are [start[k], start[k+1])
  std::vector<int> partner_index_;
  std::vector<int> partner_strip_;  ///< strip_of_point_ of partner_index_
  std::vector<int> partner_rank_;   ///< strip_rank_ of partner_strip_ (buildSweepOrder)
  std::vector<double> partner_rest_;
  /// stepLanes' band check: a spring pair by the strip of its later point, neither a root.
  struct BandPair {
    int later = 0, earlier = 0;
    /// The place in the later point's strip's sweep (column * rows + row) where the pair is kept: the later
    /// point's, or for a pair within one strip the later of its two points' places.
    int key = 0;
    /// Whether its spring pair lies within a strip, and whether the later point is the pair's b (else a).
    bool within = false, later_is_b = false;
    double near2 = 0.0, far2 = 0.0;  ///< squared band edges, 1e-9 relative to spare
  };
  static_assert(sizeof(BandPair) == 32, "a band pair in half a cache line");
  std::vector<BandPair> band_pairs_;
  std::vector<int> band_pair_start_;  ///< per strip, CSR into band_pairs_
  /// Per band pair, its spring pair's 1 / rest^2 and rest (for the scan and (11): the sweep reads nothing by
  /// spring index).
  std::vector<double> band_inv_rest2_, band_rest_;
  std::size_t max_band_pairs_ = 0;  ///< the most band pairs of one strip
  /// prepareBodies' quick reject of a body in the head frame, before its sphere-space test: a ball about
  /// its centre that holds it, and how far the body's motion over the substep carries a point near it.
  struct BodyBound {
    Vec3 centre = Vec3::Zero();
    double radius = 0.0;  ///< largest radius, with a little to spare
    double motion =
        1.0;  ///< |S_now Sinv_before - I| (Frobenius): a point's displacement per metre from the centre
    double shift = 0.0;  ///< |centre now - centre before|
  };
  /// Per distinct margin, this substep's bounds (filled in step()); SweepScratch::bounds is the current
  /// strip's, or none.
  std::vector<std::vector<BodyBound>> body_bounds_;
  /// The exact step's working state: one per sweep that may run at once (scratch_), so that the two groups
  /// of strips (buildSweepOrder) are swept on two threads. stepStrip and everything it calls write only
  /// their sweep's scratch, the points of the strip they step and its band pairs' lengths.
  struct PinchSearch {
    long sweep = -1;
    const Ellipsoid* bodies = nullptr;
    Vec3 pivot = Vec3::Zero(), previous_end = Vec3::Zero(), base = Vec3::Zero(), result = Vec3::Zero();
    double d = 0.0;
    int level = 0;
    bool have_before = false, found = false;
  };
  static constexpr int kPinchSearches = 32;
  struct SweepScratch {
    // resolveCollisions: the bodies within reach of the segment, the pivot and the previous end in the
    // sphere space of each body.
    std::vector<std::size_t> near;
    std::vector<Vec3> q_pivot, q_prev;
    std::vector<double> c_pivot, c_prev;  ///< |q|^2 - 1 of q_pivot, q_prev (bodies within reach)
    std::vector<char> pivot_inside, is_near;
    /// clearOf's tests: 0 all, 1 without the swept test, 2 the end point alone (resolveCollisions'
    /// fallbacks).
    int clear_level = 0;
    /// The previous end prepareBodies was last called with (its pivot and length are escapeBodies' own).
    Vec3 prepared_previous_end = Vec3::Zero();
    /// escapeBodies' search of the sphere of directions, remembered within a sweep: the direction it found
    /// (`found`: the first clear one, from which the arc to dir is searched) or the least penetrating one,
    /// for the same bodies, pivot, length, previous end, first candidate and test level. The search is a
    /// function of these alone, so a remembered one gives the same bits (whichever sweep remembers it).
    /// relaxStrip asks again and again for the same point when no direction clears every body (a pinch):
    /// 33,293 of 33,353 searches of the slow fuzz input were found here with 32 entries (33,005 with 8).
    std::array<PinchSearch, kPinchSearches> pinch_searches{};
    int pinch_next = 0;          ///< the entry of pinch_searches written next
    std::vector<Vec3> row_dirs;  ///< relaxStrip: a row's directions before the parallel fallback
    /// stepStrip: the points of the strip it placed itself (the others took the lanes' results, so their
    /// state already equals the lanes' buffers, as the roots' does), and whether relaxStrip moved it (then
    /// any point may differ).
    std::vector<int> exact_placed;
    bool exact_relaxed = false;
    /// relaxStrip: row r's far edge is the narrowest of rows r..tighten_to[r] (empty: each row its own).
    std::vector<int> tighten_to;
    // The current strip at the start of the substep (positions, directions, segment midpoints).
    std::vector<Vec3> start_pos, start_dir, start_mid;
    /// stepStrip: the free directions of the strip's points (before the bend limit and the constraints),
    /// which carry the hinges' rest directions down the columns.
    std::vector<Vec3> free_dir;
    /// The sweep place (strip_rank_) of the strip stepStrip is stepping: no point of a strip later in the
    /// sweep order is placed yet (placedPartner).
    int sweep_rank = std::numeric_limits<int>::max();
    /// The current strip's body bounds (body_bounds_), or none.
    const std::vector<BodyBound>* bounds = nullptr;
    /// The spring scan of the next substep, done as the sweep finds each pair's final length (stepLanes): the
    /// extremes of its pairs (its forces go to spring_force_).
    SpringExtremes extremes;
    std::vector<double> band_dist2;  ///< stepLanes: the current strip's band pairs' |a - b|^2
    std::vector<int> band_outside;   ///< stepLanes: the current strip's band pairs outside their dead band
    int collisions = 0;              ///< segments turned out of a body in this sweep
    int exact_strips = 0;            ///< strips of this sweep that took the exact step
    StepTally tally;                 ///< this sweep's part of the substep's tally
  };
  /// [0]: the sweep of the first group and the boundary (the calling thread), [1]: of the second group.
  std::array<SweepScratch, 2> scratch_;
  /// The sweep order (buildSweepOrder): the strips of the first group, of the second, then the boundary,
  /// each in strip order; sweep_group_end_[g] is the end of group g in sweep_order_. strip_rank_[s] is strip
  /// s's place in it.
  std::vector<int> sweep_order_, strip_rank_;
  std::array<std::size_t, 3> sweep_group_end_{};
  /// The blocks of the first group's strips are those before this one, the second group's from it.
  std::size_t sweep_mid_block_ = 0;
  // Bodies in the head frame, per distinct margin, now and at the previous substep.
  std::vector<std::vector<Ellipsoid>> bodies_now_;
  std::vector<std::vector<Ellipsoid>> bodies_before_;
  bool have_bodies_before_ = false;
  double max_penetration_ = 0.0;
  int penetrations_ = 0;
  double min_gap_ = 0.0;
  double min_ratio_[2] = {1.0, 1.0};
  double max_ratio_[2] = {1.0, 1.0};
  int collisions_ = 0;
  // The Lanes path: per block of lanes::kLanes chains, its rows, its margin (-1: mixed, all exact) and per
  // [block][row][lane] the control point (-1: none).
  StepPath step_path_ = StepPath::Lanes;
  int exact_strips_ = 0;
  std::vector<int> block_rows_, block_margin_, lane_point_;
  int lane_stride_rows_ = 0;  ///< rows per block in lane_point_
  /// The lanes' results, the state at the end of the substep for the strips committed from them: stepLanes
  /// swaps them with the state (positions_, direction_, rate_, velocity_) after copying in the points the
  /// exact step placed (the whole strip after relaxStrip).
  std::vector<Vec3> new_position_, new_direction_, new_rate_, new_velocity_;
  /// Per strip, the sweep (sweep_) in which it was last committed from the lanes (-1: none).
  std::vector<long> strip_committed_;
  static constexpr int kNoExact = 1 << 30;
  std::vector<lanes::LaneBody> lane_bodies_;  ///< [margin][body], this substep
  std::vector<int> strip_last_block_;         ///< per strip, the block of its last chain
  std::vector<int> block_flags_;              ///< [block][lane]: lanes::BlockJob::first_flagged_row
  std::vector<double> chain_max_rate2_;       ///< [block][lane]: lanes::BlockJob::max_rate2
  std::vector<int> strip_first_chain_;        ///< per strip, block * kLanes + lane of its column 0
  std::vector<unsigned char> lane_flag_;      ///< per point: lanes::BlockJob::out_flag
  std::vector<double> lane_constants_;        ///< per block: lanes::BlockJob::constants
  std::unique_ptr<LaneWorkers> workers_;      ///< the helper threads (setThreads), or none
  static constexpr std::size_t kMinBlocksForHelpers = 128;  ///< 512 chains, 256 strips of 2 columns
  /// Without helpers, stepLanes runs the lanes kernel over this many blocks at a time, just before it reads
  /// their strips (256 chains: about 0.4 MB of state read and written, within a core's L2). At 10,000 strips
  /// 0.952 x the time of one pass over every block first; one block at a time was 1.09-1.14 x.
  static constexpr std::size_t kBlocksPerRun = 64;
};

/// Rotation vector that turns unit a onto unit b (axis a x b, angle in [0, pi]); a deterministic
/// perpendicular axis when they are opposite.
Vec3 rotationVectorBetween(const Vec3& a, const Vec3& b);
/// Rotates v by the rotation vector w (Rodrigues).
Vec3 rotateByVector(const Vec3& w, const Vec3& v);
/// rotateByVector for w perpendicular to v (w . v = 0 within rounding, as a swing of a segment about its
/// pivot is): for the small turns (|w| < 0.1) without the term w (w . v) (1 - cos |w|) / |w|^2, which then
/// vanishes.
Vec3 rotatePerpendicular(const Vec3& w, const Vec3& v);
/// Smallest rotation taking unit a onto unit b (a deterministic 180 degree turn when opposite).
Mat3 minimalRotation(const Vec3& a, const Vec3& b);

}  // namespace hair_sim
