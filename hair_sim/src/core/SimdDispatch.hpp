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

/// Whether the AVX2 kernels run on this CPU (false without HAIR_SIM_AVX2_DISPATCH); asked once.
inline bool cpuHasAvx2() {
#if defined(HAIR_SIM_AVX2_DISPATCH)
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
#else
  return false;
#endif
}

/// Whether the CPU has AVX-512F and AVX-512VL (false without HAIR_SIM_AVX2_DISPATCH); asked once.
inline bool cpuHasAvx512vl() {
#if defined(HAIR_SIM_AVX2_DISPATCH)
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0;
  }();
  return has;
#else
  return false;
#endif
}

}  // namespace hair_sim
