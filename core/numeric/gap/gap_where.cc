// Localisation part of the gap diagnosis: where the sim model G0 departs from the records.
// Residual e = y − ŷ0 (simulation, not one-step prediction). Methods: the gap against the noise
// floor (χ² on the residual power), input–residual coherence by band (Welch; a band where e is
// coherent with u holds a linear model error — Ljung's model-error idea in the frequency domain),
// excess residual power per band, binned residual statistics against amplitude, state and time
// (η² = share of the residual variance explained by the bin means; restoring-force style).
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>
#include <sstream>

#include "core/numeric/gap/gap_diagnosis.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace {

struct Spectra {
  std::vector<double> freq_hz, uu, ee;
  std::vector<std::complex<double>> ue;
  int averages = 0;
};

// Welch auto- and cross-spectra with a Hann window and 50 % overlap, summed over records.
Spectra Welch(const std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>& segments_ue,
              double ts, int length) {
  Spectra s;
  const int bins = length / 2 + 1;
  s.uu.assign(bins, 0);
  s.ee.assign(bins, 0);
  s.ue.assign(bins, 0);
  for (int k = 0; k < bins; ++k) s.freq_hz.push_back(k / (length * ts));
  std::vector<double> window(length);
  for (int i = 0; i < length; ++i) window[i] = 0.5 - 0.5 * std::cos(2 * M_PI * i / length);
  Eigen::FFT<double> fft;
  std::vector<double> a(length), b(length);
  std::vector<std::complex<double>> fa, fb;
  for (const auto& [u, e] : segments_ue) {
    for (long start = 0; start + length <= u.size(); start += length / 2) {
      const double mu = u.segment(start, length).mean(), me = e.segment(start, length).mean();
      for (int i = 0; i < length; ++i) {
        a[i] = (u(start + i) - mu) * window[i];
        b[i] = (e(start + i) - me) * window[i];
      }
      fft.fwd(fa, a);
      fft.fwd(fb, b);
      for (int k = 0; k < bins; ++k) {
        s.uu[k] += std::norm(fa[k]);
        s.ee[k] += std::norm(fb[k]);
        s.ue[k] += std::conj(fa[k]) * fb[k];
      }
      ++s.averages;
    }
  }
  // One-sided PSD scaling: 2·|X|²·Ts / (Σw²) per average.
  double w2 = 0;
  for (double w : window) w2 += w * w;
  const double scale = 2 * ts / (w2 * std::max(1, s.averages));
  for (int k = 0; k < bins; ++k) {
    s.uu[k] *= scale;
    s.ee[k] *= scale;
    s.ue[k] *= scale;
  }
  return s;
}

GapFactor Binned(const std::string& name, const Eigen::VectorXd& e, const Eigen::VectorXd& signal,
                 const std::vector<int>& bin, const std::vector<std::string>& labels) {
  GapFactor f;
  f.name = name;
  const int nb = static_cast<int>(labels.size());
  std::vector<double> sum(nb, 0), sum2(nb, 0), signal2(nb, 0);
  std::vector<int> count(nb, 0);
  for (long k = 0; k < e.size(); ++k) {
    if (bin[k] < 0) continue;
    sum[bin[k]] += e(k);
    sum2[bin[k]] += e(k) * e(k);
    signal2[bin[k]] += signal(k) * signal(k);
    ++count[bin[k]];
  }
  double rel_min = INFINITY, rel_max = 0;
  const double mean = e.mean();
  const double total = (e.array() - mean).square().sum();
  double between = 0, rms_min = INFINITY, rms_max = 0;
  for (int b = 0; b < nb; ++b) {
    BinnedGap g;
    g.label = labels[b];
    g.samples = count[b];
    if (count[b] > 0) {
      g.mean = sum[b] / count[b];
      g.rms = std::sqrt(sum2[b] / count[b]);
      between += count[b] * (g.mean - mean) * (g.mean - mean);
      g.relative_rms = signal2[b] > 0 ? std::sqrt(sum2[b] / signal2[b]) : 0;
      if (count[b] >= 10) {
        rms_min = std::min(rms_min, g.rms);
        rms_max = std::max(rms_max, g.rms);
        if (g.relative_rms > 0) {
          rel_min = std::min(rel_min, g.relative_rms);
          rel_max = std::max(rel_max, g.relative_rms);
        }
      }
    }
    f.bins.push_back(g);
  }
  f.eta_squared = total > 0 ? between / total : 0;
  f.rms_ratio = rms_min > 0 && std::isfinite(rms_min) ? rms_max / rms_min : 1;
  f.relative_ratio = rel_min > 0 && std::isfinite(rel_min) ? rel_max / rel_min : 1;
  return f;
}

std::string Range(const char* what, double lo, double hi) {
  std::ostringstream s;
  s.precision(3);
  s << what << " in [" << lo << ", " << hi << ")";
  return s.str();
}

// Bins by quantiles of x into `n` groups of equal size.
std::vector<int> QuantileBins(const Eigen::VectorXd& x, int n, const char* what,
                              std::vector<std::string>& labels) {
  std::vector<double> sorted(x.data(), x.data() + x.size());
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> edges;
  for (int i = 0; i <= n; ++i)
    edges.push_back(sorted[std::min<size_t>(sorted.size() - 1, i * (sorted.size() - 1) / n)]);
  for (int i = 0; i < n; ++i) labels.push_back(Range(what, edges[i], edges[i + 1]));
  std::vector<int> bin(x.size());
  for (long k = 0; k < x.size(); ++k) {
    int b = static_cast<int>(std::upper_bound(edges.begin() + 1, edges.end() - 1, x(k)) - edges.begin()) - 1;
    bin[k] = std::clamp(b, 0, n - 1);
  }
  return bin;
}

}  // namespace

GapWhere LocateGap(const TransferFunction& sim_model, const std::vector<GapRecord>& records,
                   double noise_sigma) {
  GapWhere where;
  const double ts = records.front().sample_time;
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> ue;
  Eigen::VectorXd e_all, u_all, y_all, yhat_all, v_all;
  std::vector<int> reversal_all, time_bin_all;
  for (const auto& r : records) {
    const long n = r.u.size() - r.score_from;
    const Eigen::VectorXd yhat_full = Simulate(sim_model, r.u, ts).col(0);
    const Eigen::VectorXd yhat = yhat_full.tail(n), y = r.y.tail(n), u = r.u.tail(n);
    const Eigen::VectorXd e = y - yhat;
    ue.push_back({u, e});
    // Velocity of the simulated output (central differences) and reversals of its sign.
    Eigen::VectorXd v(n);
    for (long k = 0; k < n; ++k)
      v(k) = (yhat(std::min(k + 1, n - 1)) - yhat(std::max(k - 1, 0L))) / (2 * ts);
    std::vector<int> near(n, 0);
    for (long k = 1; k < n; ++k)
      if ((v(k) > 0) != (v(k - 1) > 0))
        for (long j = std::max(0L, k - 3); j < std::min(n, k + 8); ++j) near[j] = 1;
    auto append = [](Eigen::VectorXd& all, const Eigen::VectorXd& part) {
      Eigen::VectorXd joined(all.size() + part.size());
      joined << all, part;
      all = joined;
    };
    append(e_all, e);
    append(u_all, u);
    append(y_all, y);
    append(yhat_all, yhat);
    append(v_all, v);
    reversal_all.insert(reversal_all.end(), near.begin(), near.end());
    for (long k = 0; k < n; ++k) time_bin_all.push_back(static_cast<int>(4 * k / n));
  }
  const long n = e_all.size();
  where.nrmse_before = Nrmse(y_all, yhat_all)(0);
  const double rms_e = std::sqrt(e_all.squaredNorm() / n);
  if (!(noise_sigma > 0)) {
    // No noise level given: take the residual itself (gap/noise = 1, nothing called significant).
    noise_sigma = rms_e;
  }
  where.gap_to_noise = rms_e / noise_sigma;
  where.gap_significant = AboveNoiseVariance(std::pow(where.gap_to_noise, 2), n);
  if (n > 60) {
    const ResidualTest test = TestResiduals(e_all, u_all);
    where.residual_white = test.white;
    where.residual_independent = test.independent;
  }

  // Bands: 8 logarithmic bands between the Welch resolution and Nyquist.
  long shortest = n;
  for (const auto& [u, e] : ue) shortest = std::min<long>(shortest, u.size());
  int length = 256;
  while (length > 32 && length * 4 > shortest) length /= 2;
  if (shortest >= length) {
    const Spectra s = Welch(ue, ts, length);
    const double white_psd = 2 * ts * noise_sigma * noise_sigma;  // one-sided PSD of σ² noise
    // Hann windows with 50 % overlap: about 0.9 K independent averages.
    const int k_avg = std::max(2, static_cast<int>(0.9 * s.averages));
    const double coh_threshold = 1 - std::pow(0.001, 1.0 / (k_avg - 1));  // Beta(1, K−1), 99.9 %
    const double f_lo = s.freq_hz[1], f_hi = s.freq_hz.back();
    const double max_uu = *std::max_element(s.uu.begin() + 1, s.uu.end());
    const int n_bands = 8;
    for (int b = 0; b < n_bands; ++b) {
      BandGap band;
      band.f_lo_hz = f_lo * std::pow(f_hi / f_lo, double(b) / n_bands);
      band.f_hi_hz = f_lo * std::pow(f_hi / f_lo, double(b + 1) / n_bands);
      int m = 0, exceed = 0;
      double coh = 0, power = 0;
      std::vector<double> relative;
      for (size_t k = 1; k < s.freq_hz.size(); ++k) {
        if (s.freq_hz[k] < band.f_lo_hz || s.freq_hz[k] >= band.f_hi_hz * (b == n_bands - 1 ? 1.0001 : 1))
          continue;
        const double g = s.uu[k] > 0 && s.ee[k] > 0 ? std::norm(s.ue[k]) / (s.uu[k] * s.ee[k]) : 0;
        coh += g;
        exceed += g > coh_threshold;
        power += s.ee[k];
        if (s.uu[k] > 1e-3 * max_uu) {  // excited lines only: elsewhere Ê is noise over nothing
          const std::complex<double> g0 = FrequencyResponse(sim_model, 2 * M_PI * s.freq_hz[k]);
          if (std::abs(g0) > 0) relative.push_back(std::abs(s.ue[k] / s.uu[k]) / std::abs(g0));
        }
        ++m;
      }
      if (m == 0) continue;
      if (!relative.empty()) {
        std::nth_element(relative.begin(), relative.begin() + relative.size() / 2, relative.end());
        band.relative_error = relative[relative.size() / 2];
      }
      band.coherence = coh / m;
      band.coherence_threshold = coh_threshold;
      band.gap_power = power / m / white_psd;  // residual PSD relative to the noise floor
      const double expected = 0.001 * m, spread = std::sqrt(0.001 * 0.999 * m);
      band.significant = exceed > expected + 4 * spread + 1 || band.gap_power > 1.5;
      where.bands.push_back(band);
    }
  }

  // Amplitude, state and time.
  std::vector<std::string> labels;
  const Eigen::VectorXd abs_u = u_all.cwiseAbs();
  std::vector<int> bins = QuantileBins(abs_u, 4, "|u|", labels);
  where.factors.push_back(Binned("amplitude", e_all, yhat_all, bins, labels));

  labels.clear();
  const double v_scale = v_all.cwiseAbs().maxCoeff();
  std::vector<int> vbin(n);
  for (long k = 0; k < n; ++k)
    vbin[k] = std::abs(v_all(k)) < 0.01 * v_scale ? 2 : (v_all(k) > 0 ? 0 : 1);
  where.factors.push_back(
      Binned("velocity_sign", e_all, yhat_all, vbin, {"dy/dt > 0", "dy/dt < 0", "dy/dt ≈ 0 (|v| < 1 % of max)"}));
  where.factors.push_back(
      Binned("reversal", e_all, yhat_all, reversal_all, {"away from reversals", "within 3 samples before / 8 after a velocity reversal"}));

  labels.clear();
  bins = QuantileBins(yhat_all, 4, "simulated y", labels);
  where.factors.push_back(Binned("output_level", e_all, yhat_all, bins, labels));
  where.factors.push_back(Binned("time", e_all, yhat_all, time_bin_all,
                                 {"first quarter", "second quarter", "third quarter", "last quarter"}));

  std::ostringstream summary;
  summary.precision(3);
  summary << "gap/noise = " << where.gap_to_noise
          << (where.gap_significant ? " (significant)" : " (within noise)") << "; residual "
          << (where.residual_white ? "white" : "not white") << ", "
          << (where.residual_independent ? "independent of" : "correlated with") << " the input";
  std::string bands;
  for (const auto& b : where.bands)
    if (b.significant) {
      std::ostringstream t;
      t.precision(3);
      t << (bands.empty() ? "" : ", ") << b.f_lo_hz << "–" << b.f_hi_hz << " Hz";
      bands += t.str();
    }
  summary << "; bands with a gap: " << (bands.empty() ? "none" : bands);
  const GapFactor* strongest = nullptr;
  for (const auto& f : where.factors)
    if (!strongest || f.eta_squared > strongest->eta_squared) strongest = &f;
  if (strongest) summary << "; strongest dependence: " << strongest->name << " (η² = " << strongest->eta_squared << ")";
  where.summary = summary.str();
  return where;
}

}  // namespace idrig
