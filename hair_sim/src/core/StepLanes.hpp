#pragma once
/// Internal to the core: Simulator::step's structure-of-arrays path. The chains (columns of control points)
/// are taken kLanes at a time and every row of a block is advanced with loops over the lanes that the
/// compiler vectorises: the free update of the angular dynamics (1)-(7) with the forces (6), the springs'
/// force (11), the hinge, the step limit, and the tests that decide whether the exact per-strip step
/// (Simulator::stepStrip) must take over: a reaction constraint (8)-(10) in force, a bend over the limit, a
/// segment or the path of its end meeting a body. The same loops are compiled for the x86-64 baseline and
/// for AVX2 and chosen at run time; without FMA contraction both give bit-identical results.
#include <cstddef>

#include "hair_sim/core/Simulator.hpp"

namespace hair_sim {

class WindField;

namespace lanes {

/// Chains per block.
constexpr int kLanes = 4;

/// BlockJob::out_flag: the point's own step must be taken again by the exact step (a reaction constraint in
/// force, a degenerate rest frame).
constexpr unsigned char kPointFull = 2;
/// BlockJob::out_flag: the free step's direction may bend further than the limit from the rest direction: the
/// exact step limits it (the free step itself holds).
constexpr unsigned char kPointBend = 4;
/// BlockJob::out_flag: the point's new segment or its end's path is not clear of a body within reach: the
/// exact step resolves the collision from the lanes' free step.
constexpr unsigned char kPointBodies = 1;

/// One block of kLanes chains. Arrays of Vec3 are the Simulator's per-point arrays (head frame).
struct BlockJob {
  // Constants of the substep (head frame).
  double dt, k, gamma, drag, max_angle_step, cos_max_bend;
  /// Simulator::StepFrame's force0, force_mid and force_vel (row-major).
  double force0[3], force_mid[9], force_vel[9];
  /// Rows of the longest chain in the block (>= 2).
  int rows = 0;
  /// [rows][kLanes]: control point of each row of each lane (row 0: the root), -1 past a chain's end or for
  /// an empty lane.
  const int* point = nullptr;
  // The state at the start of the substep and the segment constants.
  const Vec3* positions = nullptr;
  const Vec3* direction = nullptr;
  const Vec3* velocity = nullptr;
  const Vec3* rate = nullptr;
  const Vec3* spring_force = nullptr;
  /// The block's segment constants in lane order, [row][kConstants][kLanes] (rows of the lane stride): rest
  /// direction x y z, styled direction x y z, length, inverse inertia; an idle lane's are those of a still
  /// vertical segment (0 0 1, 0 0 1, 1, 0). Filled by fillLaneConstants.
  const double* constants = nullptr;
  // The state at the end of the substep (written for the block's points).
  Vec3* out_position = nullptr;
  Vec3* out_direction = nullptr;
  Vec3* out_rate = nullptr;
  Vec3* out_velocity = nullptr;
  /// Per point, what the exact step must do there: kPointFull alone, else kPointBend and kPointBodies, either
  /// or both (5), or 0: nothing.
  unsigned char* out_flag = nullptr;
  /// Bodies for the block's thickness margin.
  const LaneBody* bodies = nullptr;
  int body_count = 0;
  bool have_before = false;
  /// Turbulence at world points (null: none), the head pose and its inverse rotation.
  const WindField* turbulence = nullptr;
  const Iso3* head_pose = nullptr;
  const Mat3* head_rotation_inverse = nullptr;
  /// Out: per lane, the first row from which the exact step must take over (0: none).
  int first_flagged_row[kLanes] = {};
  /// Out: per lane, the largest |w|^2 of its new rates (as Eigen's squaredNorm computes it), 0 for none.
  double max_rate2[kLanes] = {};
};

/// Values per lane and row in BlockJob::constants.
constexpr int kConstants = 8;

/// Fills one block's BlockJob::constants (rows: the lane stride) from the per-point segment constants;
/// point: [rows][kLanes] as BlockJob::point.
void fillLaneConstants(double* out, const int* point, int rows, const Vec3* rest_dir, const Vec3* styled_dir,
                       const double* length, const double* inv_inertia);

/// The instruction sets stepBlock may use: the best the CPU has (AVX-512VL, else AVX2, else the x86-64
/// baseline), at most AVX2, or the baseline alone. All give the same bits.
enum class Isa { Best, UpToAvx2, Baseline };
/// A kernel that advances one block.
using BlockKernel = void (*)(BlockJob& job);
/// The best kernel the CPU has within `isa` (chosen once per substep, not per block).
BlockKernel blockKernel(Isa isa);
/// The instruction set of blockKernel(isa): "AVX-512VL", "AVX2" or "x86-64" ("baseline" off x86-64).
const char* kernelName(Isa isa);

}  // namespace lanes
}  // namespace hair_sim
