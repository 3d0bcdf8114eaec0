#pragma once
/// Internal to the core: what the SIMD kernels chosen at run time share (StepLanes.cpp, Tessellator.cpp,
/// HairLook.cpp). A kernel is compiled twice, for the x86-64 baseline and with
/// __attribute__((target("avx2"))), and the AVX2 one runs when the CPU has it; without FMA contraction both
/// give the same bits. The step's lanes kernel is compiled a third time with AVX-512VL (the same 256-bit
/// vectors and operations, with 32 vector registers instead of 16), run where the CPU has it.
/// -DHAIR_SIM_NO_AVX2 keeps the baseline alone (the bit-identity tests build it that way).

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(HAIR_SIM_NO_AVX2)
#define HAIR_SIM_AVX2_DISPATCH 1
#endif

#if defined(__GNUC__) || defined(__clang__)
#define HAIR_SIM_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define HAIR_SIM_ALWAYS_INLINE inline
#endif

namespace hair_sim {

/// The instruction sets the kernels chosen at run time may use on this CPU (none without
/// HAIR_SIM_AVX2_DISPATCH); asked once.
struct CpuFeatures {
  bool avx2 = false;
  bool avx512vl = false;  ///< AVX-512F and AVX-512VL
};
inline const CpuFeatures& cpuFeatures() {
  static const CpuFeatures features = [] {
    CpuFeatures f;
#if defined(HAIR_SIM_AVX2_DISPATCH)
    __builtin_cpu_init();
    f.avx2 = __builtin_cpu_supports("avx2") != 0;
    f.avx512vl = f.avx2 && __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0;
#endif
    return f;
  }();
  return features;
}

/// Whether the AVX2 kernels run on this CPU.
inline bool cpuHasAvx2() { return cpuFeatures().avx2; }
/// Whether the step's AVX-512VL kernel runs on this CPU.
inline bool cpuHasAvx512vl() { return cpuFeatures().avx512vl; }

}  // namespace hair_sim
