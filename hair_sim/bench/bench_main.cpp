/// hair_sim_bench's main: Google Benchmark's, with the instruction sets the kernels run with on this CPU in
/// the context (the JSON's "context", the console's header): the same code is slower without AVX-512.
#include <benchmark/benchmark.h>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

int main(int argc, char** argv) {
  benchmark::AddCustomContext(
      "step_kernel", hair_sim::Simulator::kernelInstructionSet(hair_sim::Simulator::StepPath::Lanes));
  benchmark::AddCustomContext("tessellation_kernel", hair_sim::Tessellator::instructionSet());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
