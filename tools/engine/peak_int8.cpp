// peak_int8: measured int8 multiply-accumulate throughput of one core, for the engine
// benchmark's "ratio to peak" column (scripts/bench_engine.sh builds and runs it).
//
// Each test runs a long loop of independent instructions (12 accumulators, so latency is
// hidden) and reports instructions per nanosecond and MACs per nanosecond (= GMAC/s per core):
//   vpdpbusd zmm   AVX512-VNNI: 64 u8 x s8 MACs per instruction (16 lanes x 4)
//   vpdpbusd ymm   AVX-VNNI:    32 MACs (only on CPUs that have AVX-VNNI)
//   vpmaddwd zmm   AVX512BW:    32 s16 x s16 MACs (16 lanes x 2); XNNPACK's 2022 QS8/QC8
//                  avx512skx kernels sign-extend int8 to int16 and use vpmaddwd + vpaddd
//   vpmaddwd+vpaddd zmm  the pair those kernels issue per 32 MACs
//   vpmaddwd ymm   AVX2 (the avx2 kernels), 16 MACs
// Build: g++ -O2 -mavx512f -mavx512bw -mavx512vnni -mavxvnni peak_int8.cpp -o peak_int8
// Output: one line per test, "name macs_per_instruction instr_per_ns gmacs_per_core".
#include <immintrin.h>

#include <chrono>
#include <cstdint>
#include <cstdio>

namespace {

constexpr long kIters = 20'000'000;

template <typename Body>
double instrPer_ns(Body body, int instrPerIter) {
  body(kIters / 10);  // warm-up (AVX-512 license / frequency transition)
  const auto t0 = std::chrono::steady_clock::now();
  body(kIters);
  const auto t1 = std::chrono::steady_clock::now();
  const double ns = std::chrono::duration<double, std::nano>(t1 - t0).count();
  return static_cast<double>(kIters) * instrPerIter / ns;
}

volatile int sink;

// 12 independent vpdpbusd zmm (AVX512-VNNI)
void dpbusdZmm(long n) {
  asm volatile(
      "1:\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm0\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm1\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm2\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm3\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm4\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm5\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm6\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm7\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm8\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm9\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm10\n\t"
      "vpdpbusd %%zmm31, %%zmm30, %%zmm11\n\t"
      "dec %0\n\t"
      "jnz 1b\n\t"
      : "+r"(n)
      :
      : "zmm0", "zmm1", "zmm2", "zmm3", "zmm4", "zmm5", "zmm6", "zmm7", "zmm8", "zmm9", "zmm10",
        "zmm11", "zmm30", "zmm31", "cc");
}

// 12 independent vpdpbusd ymm (AVX-VNNI)
void dpbusdYmm(long n) {
  asm volatile(
      "1:\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm0\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm1\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm2\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm3\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm4\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm5\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm6\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm7\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm8\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm9\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm10\n\t"
      "%{vex%} vpdpbusd %%ymm15, %%ymm14, %%ymm11\n\t"
      "dec %0\n\t"
      "jnz 1b\n\t"
      : "+r"(n)
      :
      : "ymm0", "ymm1", "ymm2", "ymm3", "ymm4", "ymm5", "ymm6", "ymm7", "ymm8", "ymm9", "ymm10",
        "ymm11", "ymm14", "ymm15", "cc");
}

// 12 independent vpmaddwd zmm
void maddwdZmm(long n) {
  asm volatile(
      "1:\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm0\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm1\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm2\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm3\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm4\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm5\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm6\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm7\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm8\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm9\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm10\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm11\n\t"
      "dec %0\n\t"
      "jnz 1b\n\t"
      : "+r"(n)
      :
      : "zmm0", "zmm1", "zmm2", "zmm3", "zmm4", "zmm5", "zmm6", "zmm7", "zmm8", "zmm9", "zmm10",
        "zmm11", "zmm30", "zmm31", "cc");
}

// 6 x (vpmaddwd zmm -> vpaddd zmm into an accumulator), as XNNPACK's avx512skx QS8 GEMMs
void maddwdAddZmm(long n) {
  asm volatile(
      "1:\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm6\n\t"
      "vpaddd %%zmm6, %%zmm0, %%zmm0\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm7\n\t"
      "vpaddd %%zmm7, %%zmm1, %%zmm1\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm8\n\t"
      "vpaddd %%zmm8, %%zmm2, %%zmm2\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm9\n\t"
      "vpaddd %%zmm9, %%zmm3, %%zmm3\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm10\n\t"
      "vpaddd %%zmm10, %%zmm4, %%zmm4\n\t"
      "vpmaddwd %%zmm31, %%zmm30, %%zmm11\n\t"
      "vpaddd %%zmm11, %%zmm5, %%zmm5\n\t"
      "dec %0\n\t"
      "jnz 1b\n\t"
      : "+r"(n)
      :
      : "zmm0", "zmm1", "zmm2", "zmm3", "zmm4", "zmm5", "zmm6", "zmm7", "zmm8", "zmm9", "zmm10",
        "zmm11", "zmm30", "zmm31", "cc");
}

// 12 independent vpmaddwd ymm (AVX2)
void maddwdYmm(long n) {
  asm volatile(
      "1:\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm0\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm1\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm2\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm3\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm4\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm5\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm6\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm7\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm8\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm9\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm10\n\t"
      "vpmaddwd %%ymm15, %%ymm14, %%ymm11\n\t"
      "dec %0\n\t"
      "jnz 1b\n\t"
      : "+r"(n)
      :
      : "ymm0", "ymm1", "ymm2", "ymm3", "ymm4", "ymm5", "ymm6", "ymm7", "ymm8", "ymm9", "ymm10",
        "ymm11", "ymm14", "ymm15", "cc");
}

// 12 dependent imul (latency 3 cycles on Intel cores): instructions per ns * 3 = clock in GHz.
void imulChain(long n) {
  std::uint64_t x = 3;
  for (long i = 0; i < n; ++i) {
    asm volatile(
        "imul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0\n\t"
        "imul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0\n\t"
        "imul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0"
        : "+r"(x));
  }
  sink = static_cast<int>(x);
}

}  // namespace

int main() {
  std::printf("clock_ghz 0 %.3f 0\n", 3.0 * instrPer_ns(imulChain, 12));
  struct Test {
    const char* name;
    void (*body)(long);
    int instrPerIter;  // counted instructions per loop iteration (the MAC-carrying ones)
    int macsPerInstr;
  };
  const Test tests[] = {
      {"vpdpbusd_zmm", dpbusdZmm, 12, 64}, {"vpdpbusd_ymm", dpbusdYmm, 12, 32},
      {"vpmaddwd_zmm", maddwdZmm, 12, 32}, {"vpmaddwd+vpaddd_zmm", maddwdAddZmm, 6, 32},
      {"vpmaddwd_ymm", maddwdYmm, 12, 16},
  };
  for (const Test& t : tests) {
    // AVX512-VNNI CPUs without AVX-VNNI (Ice Lake / Cascade Lake servers) fault on the VEX
    // form: leave the line out there.
    if (t.body == dpbusdYmm && !__builtin_cpu_supports("avxvnni"))
      continue;
    const double ipn = instrPer_ns(t.body, t.instrPerIter);
    std::printf("%s %d %.3f %.1f\n", t.name, t.macsPerInstr, ipn, ipn * t.macsPerInstr);
  }
  return 0;
}
