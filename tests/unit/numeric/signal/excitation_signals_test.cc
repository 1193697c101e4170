// Excitation signals: exact periods, spectra, crest factors, block == sample by sample.
// Reference values are closed forms (PRBS autocorrelation, Parseval, the exponential and
// step formulas), never the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "core/numeric/signal/excitation.h"

namespace idrig {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRoundOff = 1e-12;        // values computed by the same formula, other path
constexpr double kSpectralLeak = 1e-9;     // |X| on unexcited bins relative to N
constexpr double kLineAmplitude = 1e-9;    // relative error of an excited line's amplitude

ExcitationSpec Spec(const std::string& text) { return ParseExcitationSpec(text); }

std::vector<double> SampleBySample(const ExcitationSpec& spec, double fs, int n) {
  ExcitationGenerator generator(spec, fs);
  std::vector<double> out;
  for (int k = 0; k < n; ++k) out.push_back(generator.Next());
  return out;
}

TEST(ExcitationTest, BlockEqualsSampleBySampleForEveryKind) {
  const double fs = 100.0;
  const int n = 5000;
  for (const std::string text :
       {"step:amp=2,at=1", "exp:T=1,amp=1,at=0.5", "sine:f=1,amp=0.5,phase=0.3",
        "multisine:f0=0.1,lines=1-20,set=odd,phase=schroeder,amp=1",
        "multisine:f0=0.2,lines=1-8,phase=random,seed=42,amp=0.3,offset=1",
        "prbs:bits=10,amp=1", "prbs:bits=7,amp=2,fc=30,offset=-1", "rbs:fc=7,seed=3,amp=1",
        "rbs:seed=9", "chirp:f0=0.1,f1=5,amp=1,T=20", "chirp:f0=0.1,f1=5,T=20,sweep=log"}) {
    SCOPED_TRACE(text);
    const ExcitationSpec spec = Spec(text);
    const Eigen::VectorXd block = GenerateExcitation(spec, fs, n);
    const std::vector<double> online = SampleBySample(spec, fs, n);
    for (int k = 0; k < n; ++k) ASSERT_EQ(block[k], online[k]) << "sample " << k;
    // Reset restarts the same sequence.
    ExcitationGenerator generator(spec, fs);
    for (int k = 0; k < 37; ++k) generator.Next();
    generator.Reset();
    EXPECT_EQ(generator.Next(), block[0]);
  }
}

TEST(ExcitationTest, StepAndExponentialClosedForm) {
  const double fs = 10.0;
  const Eigen::VectorXd step = GenerateExcitation(Spec("step:amp=2,at=1"), fs, 30);
  for (int k = 0; k < 30; ++k) EXPECT_EQ(step[k], k >= 10 ? 2.0 : 0.0) << k;
  // Fig. 7 of [Ivanovsky]: u = 1 − e^(−t).
  const Eigen::VectorXd u = GenerateExcitation(Spec("exp:T=1,amp=1"), fs, 50);
  for (int k = 0; k < 50; ++k) EXPECT_NEAR(u[k], 1.0 - std::exp(-k / fs), kRoundOff);
}

TEST(ExcitationTest, PeriodsAreExact) {
  const double fs = 50.0;
  EXPECT_DOUBLE_EQ(ExcitationPeriod(Spec("prbs:bits=6,fc=10"), fs), 63.0 / 10.0);
  EXPECT_DOUBLE_EQ(ExcitationPeriod(Spec("prbs:bits=6"), fs), 63.0 / fs);
  EXPECT_DOUBLE_EQ(ExcitationPeriod(Spec("multisine:f0=0.25,lines=1-5"), fs), 4.0);
  EXPECT_DOUBLE_EQ(ExcitationPeriod(Spec("chirp:f0=1,f1=2,T=3"), fs), 3.0);
  EXPECT_DOUBLE_EQ(ExcitationPeriod(Spec("step:amp=1"), fs), 0.0);
  // Whole periods in samples repeat exactly (to round-off of the phase reduction).
  for (const std::string text : {"multisine:f0=0.25,lines=1-9,phase=schroeder",
                                 "chirp:f0=1,f1=2,T=3,sweep=log", "prbs:bits=6,fc=10"}) {
    SCOPED_TRACE(text);
    const ExcitationSpec spec = Spec(text);
    const int period = static_cast<int>(std::lround(ExcitationPeriod(spec, fs) * fs));
    const Eigen::VectorXd u = GenerateExcitation(spec, fs, 3 * period);
    for (int k = 0; k < 2 * period; ++k) EXPECT_NEAR(u[k + period], u[k], 1e-9) << k;
  }
}

TEST(ExcitationTest, PrbsPeriodAndTwoValuedAutocorrelation) {
  for (int bits = 2; bits <= 12; ++bits) {
    SCOPED_TRACE(bits);
    const int period = (1 << bits) - 1;
    const double amp = 1.5;
    ExcitationSpec spec = Spec("prbs:bits=" + std::to_string(bits) + ",amp=1.5");
    const Eigen::VectorXd u = GenerateExcitation(spec, 1.0, 2 * period);
    // Exact period N = 2^n − 1 and no shorter one.
    for (int k = 0; k < period; ++k) ASSERT_EQ(u[k + period], u[k]);
    for (int p = 1; p < period; ++p) {
      if (period % p) continue;
      bool repeats = true;
      for (int k = 0; k < period - p && repeats; ++k) repeats = u[k + p] == u[k];
      EXPECT_FALSE(repeats) << "shorter period " << p;
    }
    // Balance: 2^(n−1) ones and 2^(n−1) − 1 minus-ones, so Σu = amp.
    EXPECT_NEAR(u.head(period).sum(), amp, kRoundOff);
    // Circular autocorrelation: R(0) = N·a², R(k) = −a² for k = 1..N−1 (m-sequence).
    for (int lag = 0; lag < period; ++lag) {
      double r = 0.0;
      for (int k = 0; k < period; ++k) r += u[k] * u[(k + lag) % period];
      EXPECT_NEAR(r, lag == 0 ? period * amp * amp : -amp * amp, kRoundOff * period) << lag;
    }
  }
}

TEST(ExcitationTest, PrbsLongRegistersHaveFullPeriod) {
  // Count LFSR steps until the state returns: the values repeat with period 2^n − 1.
  for (int bits : {15, 16, 17, 18}) {
    SCOPED_TRACE(bits);
    const int period = (1 << bits) - 1;
    const Eigen::VectorXd u = GenerateExcitation(Spec("prbs:bits=" + std::to_string(bits)), 1.0,
                                                 period + bits);
    for (int k = 0; k < bits; ++k) ASSERT_EQ(u[period + k], u[k]);
    EXPECT_NEAR(u.head(period).sum(), 1.0, kRoundOff);  // balance of an m-sequence
  }
}

// GF(2) polynomial arithmetic for an independent primitivity check of the tap table.
uint64_t MulMod(uint64_t a, uint64_t b, uint64_t p, int degree) {
  uint64_t result = 0;
  while (b) {
    if (b & 1) result ^= a;
    b >>= 1;
    a <<= 1;
    if (a >> degree & 1) a ^= p;
  }
  return result;
}
uint64_t PowMod(uint64_t e, uint64_t p, int degree) {  // x^e mod p
  uint64_t result = 1, base = 2;
  while (e) {
    if (e & 1) result = MulMod(result, base, p, degree);
    base = MulMod(base, base, p, degree);
    e >>= 1;
  }
  return result;
}

TEST(ExcitationTest, PrbsTapTableIsPrimitive) {
  for (int bits = 2; bits <= 32; ++bits) {
    SCOPED_TRACE(bits);
    uint64_t p = 1;  // constant term
    for (int e : PrbsPolynomialTaps(bits)) p |= uint64_t{1} << e;
    const uint64_t order = (uint64_t{1} << bits) - 1;
    ASSERT_EQ(PowMod(order, p, bits), 1u);
    // x has order exactly 2^n − 1: x^(order/q) != 1 for every prime q | order.
    uint64_t rest = order;
    for (uint64_t q = 2; q * q <= rest; ++q) {
      if (rest % q) continue;
      EXPECT_NE(PowMod(order / q, p, bits), 1u) << "prime factor " << q;
      while (rest % q == 0) rest /= q;
    }
    if (rest > 1) {
      EXPECT_NE(PowMod(order / rest, p, bits), 1u) << "prime factor " << rest;
    }
  }
}

TEST(ExcitationTest, MultisinePowerExactlyOnChosenLines) {
  const double fs = 10.0;  // f0 = 0.1 Hz: one base period = 100 samples
  for (const std::string set : {"all", "odd", "oddodd"}) {
    SCOPED_TRACE(set);
    const ExcitationSpec spec =
        Spec("multisine:f0=0.1,lines=1-20,set=" + set + ",phase=schroeder,amps=" +
             [] {
               std::string a;
               for (int i = 1; i <= 20; ++i) a += (i > 1 ? ";" : "") + std::to_string(0.5 + 0.05 * i);
               return a;
             }());
    const int n = 100;
    const Eigen::VectorXd u = GenerateExcitation(spec, fs, n);
    Eigen::FFT<double> fft;
    std::vector<double> time(u.data(), u.data() + n);
    std::vector<std::complex<double>> spectrum;
    fft.fwd(spectrum, time);
    std::vector<double> expected(n / 2, 0.0);
    for (int line = 1; line <= 20; ++line) {
      const bool excited = set == "all" || (set == "odd" && line % 2 == 1) ||
                           (set == "oddodd" && line % 4 == 1);
      if (excited) expected[line] = 0.5 + 0.05 * line;  // amplitude ρ_k
    }
    for (int bin = 0; bin < n / 2; ++bin) {
      const double amplitude = 2.0 * std::abs(spectrum[bin]) / n;
      if (expected[bin] > 0.0) {
        EXPECT_NEAR(amplitude, expected[bin], kLineAmplitude * expected[bin]) << bin;
      } else {
        EXPECT_LT(std::abs(spectrum[bin]), kSpectralLeak * n) << bin;
      }
    }
    // The detection lines are exactly the unexcited ones.
    for (int line : MultisineDetectionLines(spec)) EXPECT_EQ(expected[line], 0.0) << line;
    const size_t free_expected = set == "all" ? 0 : set == "odd" ? 10 : 15;
    EXPECT_EQ(MultisineDetectionLines(spec).size(), free_expected);
  }
}

TEST(ExcitationTest, MultisineZeroPhaseIsEquationFive) {
  // Eq. (5) of [Aleksandrov]: u = Σ ρ_k sin(ω_k t).
  const ExcitationSpec spec = Spec("multisine:w0=0.5,lines=1;3;7,amps=1;0.5;0.25,amp=2");
  const Eigen::VectorXd u = GenerateExcitation(spec, 20.0, 400);
  for (int k = 0; k < 400; ++k) {
    const double t = k / 20.0;
    const double expected =
        2.0 * (std::sin(0.5 * t) + 0.5 * std::sin(1.5 * t) + 0.25 * std::sin(3.5 * t));
    EXPECT_NEAR(u[k], expected, 1e-12) << k;
  }
}

double CrestFactor(const Eigen::VectorXd& u) {
  return u.cwiseAbs().maxCoeff() / std::sqrt(u.squaredNorm() / u.size());
}

TEST(ExcitationTest, SchroederCrestFactorBelowZeroPhase) {
  const double fs = 1000.0;  // 10 000 samples per base period
  const auto zero = GenerateExcitation(Spec("multisine:f0=0.1,lines=1-20,phase=zero"), fs, 10000);
  const auto schroeder =
      GenerateExcitation(Spec("multisine:f0=0.1,lines=1-20,phase=schroeder"), fs, 10000);
  const auto random =
      GenerateExcitation(Spec("multisine:f0=0.1,lines=1-20,phase=random,seed=7"), fs, 10000);
  // RMS is sqrt(20/2) for every phase choice (Parseval).
  EXPECT_NEAR(std::sqrt(schroeder.squaredNorm() / 10000), std::sqrt(10.0), 1e-9);
  EXPECT_LT(CrestFactor(schroeder), CrestFactor(zero));
  EXPECT_LT(CrestFactor(schroeder), 2.0);  // Schroeder: ~1.7 for a flat 20-line spectrum
  EXPECT_GT(CrestFactor(zero), 3.0);
  EXPECT_GT(CrestFactor(random), 0.0);
  // RMS scaling.
  const auto rms = GenerateExcitation(
      Spec("multisine:f0=0.1,lines=1-20,phase=schroeder,scale=rms,amp=0.2"), fs, 10000);
  EXPECT_NEAR(std::sqrt(rms.squaredNorm() / 10000), 0.2, 1e-9);
}

TEST(ExcitationTest, RandomBinaryIsSeededAndBalanced) {
  const auto a = GenerateExcitation(Spec("rbs:seed=1"), 1.0, 20000);
  const auto b = GenerateExcitation(Spec("rbs:seed=1"), 1.0, 20000);
  const auto c = GenerateExcitation(Spec("rbs:seed=2"), 1.0, 20000);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_LT(std::abs(a.mean()), 4.0 / std::sqrt(20000.0));  // 4σ of a fair coin
  for (int k = 0; k < 20000; ++k) ASSERT_EQ(std::abs(a[k]), 1.0);
  // fc = fs/4: each bit held for 4 samples.
  const auto held = GenerateExcitation(Spec("rbs:seed=1,fc=0.25"), 1.0, 400);
  for (int k = 0; k < 400; ++k) ASSERT_EQ(held[k], held[k - k % 4]);
}

TEST(ExcitationTest, ChirpInstantaneousFrequency) {
  // Linear sweep: phase 2π(f0 t + (f1 − f0) t²/(2T)).
  const auto u = GenerateExcitation(Spec("chirp:f0=0.5,f1=4,T=10,amp=1"), 100.0, 1000);
  for (int k = 0; k < 1000; k += 7) {
    const double t = k / 100.0;
    EXPECT_NEAR(u[k], std::sin(2 * kPi * (0.5 * t + 3.5 * t * t / 20.0)), 1e-9) << k;
  }
  // Log sweep: frequency f0·(f1/f0)^(t/T).
  const auto v = GenerateExcitation(Spec("chirp:f0=0.5,f1=4,T=10,sweep=log"), 100.0, 1000);
  for (int k = 0; k < 1000; k += 7) {
    const double t = k / 100.0;
    const double phase = 2 * kPi * 0.5 * 10.0 / std::log(8.0) * (std::pow(8.0, t / 10.0) - 1);
    EXPECT_NEAR(v[k], std::sin(phase), 1e-9) << k;
  }
}

}  // namespace
}  // namespace idrig
