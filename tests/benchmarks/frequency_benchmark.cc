// Frequency-domain methods of seed 002 ([Balda]): speed, bias and real data. Not run by ctest;
// driven by tests/benchmarks/frequency_vs_octave.sh, which runs Octave's invfreqs on the same
// files in the same run. Subcommands:
//   frequency_benchmark speed OUT.csv   Levy / Levy+SK on 10^4 lines, order 10 (writes the FRF)
//   frequency_benchmark bias OUT.csv    seed 001's plant, 1 % noise: Levy vs SK pole error
//   frequency_benchmark balda [SEEDS]   pole-residue on Balda's seven eigenvalues, noise 0/0.1/1 %
//   frequency_benchmark real [SHARED]   frf_accelerance (pole-residue), robot_arm (Welch + fits)
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/frf_csv.h"
#include "core/numeric/frequency_domain/pole_residue.h"
#include "core/numeric/frequency_domain/stable_nls.h"

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

// Balda's seven eigenvalues (PAPER_NUMBERS.md), 500 lines over 10–52 Hz, relative complex
// noise, weights 1/|g|, residues as in tests/unit/frequency/pole_residue_test.cc: a = −iσh,
// h = (1, .8, .6, .7, .9, .8, .6) (same sign), or with the 315 pair opposite (a₆ ×4,
// a₇ = −1.5·a₆). Per noise level: worst relative error of Re s / Im s over modes 1–5 and over
// the pair (median and worst over the seeds; the fitted pole nearest each eigenvalue), and how
// many seeds meet 5 % / 0.5 % on all seven.
int Balda(int seeds) {
  const double table[7][2] = {{-1.33, 71.94}, {-18.24, 70.53}, {-2.05, 104.57}, {-2.28, 110.53},
                              {-22.37, 251.90}, {-19.84, 315.03}, {-32.15, 314.88}};
  const double height[7] = {1.0, 0.8, 0.6, 0.7, 0.9, 0.8, 0.6};
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(500, 2 * kPi * 10.0, 2 * kPi * 52.0);
  std::printf("pole-residue on Balda's seven eigenvalues, 500 lines 10-52 Hz, weights 1/|g|, %d seeds\n", seeds);
  std::printf("residues  noise  | modes 1-5 worst Re / Im (median, worst) | 315 pair worst Re / Im (median, worst) | all 7 within 5 %% / 0.5 %%\n");
  for (const bool opposite : {false, true}) {
    Complex a[7];
    for (int v = 0; v < 7; ++v) a[v] = Complex(0.0, table[v][0] * height[v]);
    if (opposite) {
      a[5] *= 4.0;
      a[6] = -1.5 * a[5];
    }
    Eigen::VectorXcd g0 = Eigen::VectorXcd::Zero(500);
    for (int v = 0; v < 7; ++v) {
      const Complex s(table[v][0], table[v][1]);
      for (int k = 0; k < 500; ++k)
        g0(k) += a[v] / (Complex(0, w(k)) - s) + std::conj(a[v]) / (Complex(0, w(k)) - std::conj(s));
    }
    for (double noise : {0.0, 0.001, 0.01}) {
      std::vector<double> worst[4];
      int within = 0, extra = 0, not_converged = 0;
      const int runs = noise == 0.0 ? 1 : seeds;
      for (int seed = 1; seed <= runs; ++seed) {
        std::mt19937_64 rng(seed);
        std::normal_distribution<double> n01;
        Eigen::VectorXcd g = g0;
        for (int k = 0; k < 500; ++k) g(k) += noise * std::abs(g(k)) * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
        PoleResidueOptions o;
        o.weights = g.cwiseAbs().cwiseInverse();
        const PoleResidueResult r = FitPoleResidue(MakeSisoFrf(w, g), o);
        double e[4] = {0, 0, 0, 0};  // Re 1-5, Im 1-5, Re pair, Im pair
        for (int v = 0; v < 7; ++v) {
          const Complex t(table[v][0], table[v][1]);
          const Mode* b = &r.modes[0];
          for (const auto& m : r.modes)
            if (std::abs(m.eigenvalue - t) < std::abs(b->eigenvalue - t)) b = &m;
          const int grp = v >= 5 ? 2 : 0;
          e[grp] = std::max(e[grp], std::abs(b->eigenvalue.real() - t.real()) / std::abs(t.real()));
          e[grp + 1] = std::max(e[grp + 1], std::abs(b->eigenvalue.imag() - t.imag()) / t.imag());
        }
        for (int i = 0; i < 4; ++i) worst[i].push_back(100 * e[i]);
        within += std::max(e[0], e[2]) < 0.05 && std::max(e[1], e[3]) < 0.005;
        extra += r.modes.size() > 7;
        not_converged += !r.ok();
      }
      auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
      };
      auto max = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
      std::printf("%-9s %4.1f %%  | %5.2f, %5.2f %% / %5.3f, %5.3f %%       | %5.1f, %5.1f %% / %5.2f, %5.2f %%        | %d/%d (%d with an 8th pole, %d not converged)\n",
                  opposite ? "opposite" : "same-sign", 100 * noise, median(worst[0]), max(worst[0]), median(worst[1]),
                  max(worst[1]), median(worst[2]), max(worst[2]), median(worst[3]), max(worst[3]), within, runs, extra,
                  not_converged);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "speed" && argc > 2) return Speed(argv[2]);
  if (cmd == "bias" && argc > 2) return Bias(argv[2]);
  if (cmd == "balda") return Balda(argc > 2 ? std::atoi(argv[2]) : 20);
  if (cmd == "real") return Real(argc > 2 ? argv[2] : IDRIG_SHARED_DIR);
  std::fprintf(stderr, "usage: frequency_benchmark speed OUT.csv | bias OUT.csv | balda [SEEDS] | real [SHARED_DIR]\n");
  return 2;
}
