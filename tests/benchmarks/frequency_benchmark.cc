// Frequency-domain methods of seed 002 ([Balda]): speed, bias and real data. Not run by ctest;
// driven by tests/benchmarks/frequency_vs_octave.sh, which runs Octave's invfreqs on the same
// files in the same run. Subcommands:
//   frequency_benchmark speed OUT.csv   Levy / Levy+SK on 10^4 lines, order 10 (writes the FRF)
//   frequency_benchmark bias OUT.csv    seed 001's plant, 1 % noise: Levy vs SK pole error
//   frequency_benchmark balda           pole-residue on Balda's seven eigenvalues, noise 0/0.1/1 %
//   frequency_benchmark real [SHARED]   frf_accelerance (pole-residue), robot_arm (Welch + fits)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/frf_csv.h"
#include "core/numeric/pole_residue.h"
#include "core/numeric/stable_nls.h"

namespace {

using namespace idrig;
using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

double MaxPoleDistance(const Eigen::VectorXcd& truth, const Eigen::VectorXcd& est) {
  double worst = 0.0;
  for (int i = 0; i < truth.size(); ++i) {
    double best = 1e300;
    for (int j = 0; j < est.size(); ++j) best = std::min(best, std::abs(truth(i) - est(j)));
    worst = std::max(worst, best);
  }
  return worst;
}

Frf NoisyFrf(const TransferFunction& tf, const Eigen::VectorXd& w, double noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXcd g = FrequencyResponse(tf, w);
  const double sigma = noise * g.cwiseAbs().maxCoeff();
  for (int k = 0; k < g.size(); ++k) g(k) += sigma * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
  return MakeSisoFrf(w, g);
}

Eigen::VectorXd LogLines(int n, double lo, double hi) {
  Eigen::VectorXd w(n);
  for (int k = 0; k < n; ++k) w(k) = lo * std::pow(hi / lo, k / (n - 1.0));
  return w;
}

void WriteTruePoles(const std::string& path, const Eigen::VectorXcd& poles) {
  std::ofstream out(path);
  out.precision(17);
  for (int i = 0; i < poles.size(); ++i) out << poles(i).real() << "," << poles(i).imag() << "\n";
}

template <class F>
double MedianSeconds(int runs, F f) {
  std::vector<double> t;
  for (int i = 0; i < runs; ++i) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

int Speed(const std::string& out) {
  // Order 10: five modes ω_n = 1, 2.5, 5, 9, 15 rad/s, ζ = 0.05; numerator degree 8.
  Eigen::VectorXcd poles(10);
  const double wn[5] = {1.0, 2.5, 5.0, 9.0, 15.0};
  for (int m = 0; m < 5; ++m) {
    const Complex s(-0.05 * wn[m], wn[m] * std::sqrt(1 - 0.0025));
    poles(2 * m) = s;
    poles(2 * m + 1) = std::conj(s);
  }
  TransferFunction tf;
  tf.den = PolynomialFromRoots(poles);
  Eigen::VectorXcd zeros(8);
  const double zn[4] = {1.7, 3.5, 7.0, 12.0};
  for (int m = 0; m < 4; ++m) {
    zeros(2 * m) = Complex(-0.1 * zn[m], zn[m]);
    zeros(2 * m + 1) = Complex(-0.1 * zn[m], -zn[m]);
  }
  tf.num = PolynomialFromRoots(zeros) * tf.den(tf.den.size() - 1) / PolynomialFromRoots(zeros)(8);
  const Frf frf = NoisyFrf(tf, LogLines(10000, 0.3, 30.0), 0.001, 1);
  WriteFrfCsv(frf, out);
  WriteTruePoles(out + ".poles", poles);
  LevyOptions o;
  o.denominator_degree = 10;
  o.numerator_degree = 8;
  o.max_sk_iterations = 0;
  LevyResult levy, sk;
  const double t_levy = MedianSeconds(5, [&] { levy = FitLevy(frf, o); });
  o.max_sk_iterations = 30;
  const double t_sk = MedianSeconds(5, [&] { sk = FitLevy(frf, o); });
  std::printf("idrig speed: 10^4 lines, order 10/8, 0.1 %% noise\n");
  std::printf("  plain Levy: %.4f s (median of 5), max pole error %.3g\n", t_levy, MaxPoleDistance(poles, levy.poles));
  std::printf("  Levy + SK : %.4f s (median of 5), %d SK iterations, %s, max pole error %.3g\n", t_sk,
              sk.sk_iterations, sk.message.c_str(), MaxPoleDistance(poles, sk.poles));
  return 0;
}

int Bias(const std::string& out) {
  TransferFunction plant;
  plant.num = Eigen::Vector2d(0.5, 1.0);
  plant.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  const Eigen::VectorXcd poles = Poles(plant);
  std::printf("idrig bias: seed 001 plant, 200 lines 0.05-20 rad/s, noise sigma = 1 %% of max|G|\n");
  double e_levy = 0, e_sk = 0, e_nls = 0;
  const int runs = 20;
  for (int seed = 1; seed <= runs; ++seed) {
    const Frf frf = NoisyFrf(plant, LogLines(200, 0.05, 20.0), 0.01, seed);
    if (seed == 1) {
      WriteFrfCsv(frf, out);
      WriteTruePoles(out + ".poles", poles);
    }
    LevyOptions o;
    o.denominator_degree = 3;
    o.numerator_degree = 1;
    o.max_sk_iterations = 0;
    const double a = MaxPoleDistance(poles, FitLevy(frf, o).poles);
    o.max_sk_iterations = 50;
    const double b = MaxPoleDistance(poles, FitLevy(frf, o).poles);
    StableNlsOptions so;
    so.denominator_degree = 3;
    so.numerator_degree = 1;
    const double c = MaxPoleDistance(poles, FitStableNls(frf, so).poles);
    if (seed == 1) std::printf("  seed 1 (file written): max pole error Levy %.4g, SK %.4g, stable NLS %.4g\n", a, b, c);
    e_levy += a / runs;
    e_sk += b / runs;
    e_nls += c / runs;
  }
  std::printf("  mean over %d seeds: Levy %.4g, SK %.4g (ratio %.1f), stable NLS %.4g\n", runs, e_levy, e_sk,
              e_levy / e_sk, e_nls);
  return 0;
}

// Python-style complex numbers, one per line: (a+bj).
Eigen::VectorXcd ReadComplexLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<Complex> v;
  std::string line;
  while (std::getline(in, line)) {
    double re = 0, im = 0;
    if (std::sscanf(line.c_str(), " (%lf%lfj)", &re, &im) == 2) v.emplace_back(re, im);
  }
  return Eigen::Map<Eigen::VectorXcd>(v.data(), v.size());
}

int Real(const std::string& shared) {
  const std::string acc = shared + "/data/frf_accelerance/meas_point_1.txt";
  if (!std::ifstream(acc)) {
    std::printf("real data: %s absent, skipped\n", acc.c_str());
    return 0;
  }
  for (int point = 1; point <= 3; ++point) {
    const Eigen::VectorXcd all = ReadComplexLines(shared + "/data/frf_accelerance/meas_point_" + std::to_string(point) + ".txt");
    // 0..1000 Hz in 1 Hz steps; fit 50..1000 Hz (DC line and the lowest lines dropped).
    const int first = 50, lines = static_cast<int>(all.size()) - first;
    Eigen::VectorXd w(lines);
    for (int k = 0; k < lines; ++k) w(k) = 2 * kPi * (first + k);
    const Frf frf = MakeSisoFrf(w, all.tail(lines));
    PoleResidueOptions o;
    o.peak_tolerance = 0.3;
    const auto t0 = std::chrono::steady_clock::now();
    const PoleResidueResult r = FitPoleResidue(frf, o);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("frf_accelerance meas_point_%d (50-1000 Hz, %d lines): %s, fit %.1f %%, %.3f s\n", point, lines,
                r.message.c_str(), r.fit_percent, t);
    for (const Mode& m : r.modes)
      std::printf("    f_n %7.1f Hz  zeta %.4f  Q %7.1f%s\n", m.natural_frequency / (2 * kPi), m.damping_ratio, m.q,
                  m.fictitious ? "  (fictitious)" : "");
  }
  const std::string robot = shared + "/data/daisy/robot_arm.dat";
  std::ifstream in(robot);
  if (!in) {
    std::printf("robot_arm.dat absent, skipped\n");
    return 0;
  }
  std::vector<double> u, y;
  double a, b;
  while (in >> a >> b) {
    u.push_back(a);
    y.push_back(b);
  }
  const int n = static_cast<int>(u.size());
  const IoRecord rec = MakeIoRecord(Eigen::Map<Eigen::MatrixXd>(u.data(), n, 1), Eigen::Map<Eigen::MatrixXd>(y.data(), n, 1), 1.0);
  WelchOptions wo;
  wo.segment_length = 256;
  const Frf frf = EstimateFrfWelch(rec, wo);
  std::printf("robot_arm.dat: %d samples (Ts unknown: 1 s used, ω in rad/sample), Welch H1 with %d segments of 256\n", n,
              frf.averages);
  double coh = 0;
  for (int k = 0; k < frf.NumLines(); ++k) coh += frf.coherence(k, 0) / frf.NumLines();
  std::printf("  mean coherence %.3f; |H| peaks at ω =", coh);
  for (int i : FindPeaks(frf.Element().cwiseAbs(), 0.3)) std::printf(" %.3f", frf.omega(i));
  std::printf(" rad/sample\n");
  // Fit the continuous-frequency models on the band below 0.9·Nyquist.
  Frf band;
  std::vector<int> keep;
  for (int k = 0; k < frf.NumLines(); ++k)
    if (frf.omega(k) < 0.9 * kPi) keep.push_back(k);
  band.omega.resize(keep.size());
  for (size_t i = 0; i < keep.size(); ++i) {
    band.omega(i) = frf.omega(keep[i]);
    band.h.push_back(frf.h[keep[i]]);
  }
  for (int order : {4, 6}) {
    LevyOptions lo;
    lo.denominator_degree = order;
    lo.numerator_degree = order - 1;
    const LevyResult sk = FitLevy(band, lo);
    StableNlsOptions so;
    so.denominator_degree = order;
    so.numerator_degree = order - 1;
    so.square_numerator = false;
    const StableNlsResult nls = FitStableNls(band, so);
    std::printf("  order %d: Levy+SK fit %.1f %% (stable %d, %s); stable NLS fit %.1f %% (stable %d, %s)\n", order,
                sk.fit_percent, sk.stable, ToString(sk.status), nls.fit_percent, nls.stable, ToString(nls.status));
  }
  return 0;
}

// Balda's seven eigenvalues (PAPER_NUMBERS.md), residues a = −iσh as in
// tests/unit/frequency/pole_residue_test.cc, 500 lines over 10–52 Hz, relative complex noise:
// worst relative error of Re s and Im s over the seven, per seed and noise level.
int Balda() {
  const double table[7][2] = {{-1.33, 71.94}, {-18.24, 70.53}, {-2.05, 104.57}, {-2.28, 110.53},
                              {-22.37, 251.90}, {-19.84, 315.03}, {-32.15, 314.88}};
  const double height[7] = {1.0, 0.8, 0.6, 0.7, 0.9, 0.8, 0.6};
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(500, 2 * kPi * 10.0, 2 * kPi * 52.0);
  Eigen::VectorXcd g0 = Eigen::VectorXcd::Zero(500);
  for (int v = 0; v < 7; ++v) {
    const Complex s(table[v][0], table[v][1]), a(0.0, table[v][0] * height[v]);
    for (int k = 0; k < 500; ++k) g0(k) += a / (Complex(0, w(k)) - s) + std::conj(a) / (Complex(0, w(k)) - std::conj(s));
  }
  std::printf("pole-residue on Balda's seven eigenvalues, 500 lines 10-52 Hz: worst error over modes 1-5 | over the 315 pair\n");
  for (double noise : {0.0, 0.001, 0.01}) {
    for (int seed = 1; seed <= 5; ++seed) {
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> n01;
      Eigen::VectorXcd g = g0;
      for (int k = 0; k < 500; ++k) g(k) += noise * std::abs(g(k)) * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
      const PoleResidueResult r = FitPoleResidue(MakeSisoFrf(w, g), {});
      double re[2] = {0, 0}, im[2] = {0, 0};
      for (int v = 0; v < 7; ++v) {
        const Complex t(table[v][0], table[v][1]);
        const Mode* b = &r.modes[0];
        for (const auto& m : r.modes)
          if (std::abs(m.eigenvalue - t) < std::abs(b->eigenvalue - t)) b = &m;
        const int grp = v >= 5;
        re[grp] = std::max(re[grp], std::abs(b->eigenvalue.real() - t.real()) / std::abs(t.real()));
        im[grp] = std::max(im[grp], std::abs(b->eigenvalue.imag() - t.imag()) / t.imag());
      }
      std::printf("  noise %.1f %%, seed %d: %zu poles; Re %.2f %%, Im %.3f %% | Re %.1f %%, Im %.2f %%\n", 100 * noise,
                  seed, r.modes.size(), 100 * re[0], 100 * im[0], 100 * re[1], 100 * im[1]);
      if (noise == 0.0) break;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "speed" && argc > 2) return Speed(argv[2]);
  if (cmd == "bias" && argc > 2) return Bias(argv[2]);
  if (cmd == "balda") return Balda();
  if (cmd == "real") return Real(argc > 2 ? argv[2] : IDRIG_SHARED_DIR);
  std::fprintf(stderr, "usage: frequency_benchmark speed OUT.csv | bias OUT.csv | balda | real [SHARED_DIR]\n");
  return 2;
}
