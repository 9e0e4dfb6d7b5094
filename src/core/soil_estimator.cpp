// Online estimation of a soil's material from the physical cutting force.
// See soil_estimator.hpp; the method and its sources: docs/teleoperation.md
// ("The soil estimate").
#include "terracut/core/soil_estimator.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {

namespace {

// The linear parameters are fitted in kN/m^3 and kPa against forces in kN,
// so that the covariance and the residuals stay near unity.
constexpr double kToKilo = 1e-3;

bool finite_all(const SoilSample& s) {
  return std::isfinite(s.width_m) && std::isfinite(s.depth_m) && std::isfinite(s.pile_m) &&
         std::isfinite(s.rake_deg) && std::isfinite(s.horizontal_n) && std::isfinite(s.vertical_n);
}

// One scalar equation y = x . theta into an RLS state, with forgetting
// lambda. Returns the term the equation adds to the weighted cost: the a
// priori residual squared, lambda e^2 / (lambda + x'Px) (the exact recursion
// of the forgetting-weighted least-squares cost).
double rls_update(std::array<double, 3>& theta, std::array<double, 9>& p,
                  const std::array<double, 3>& x, double y, double lambda) {
  std::array<double, 3> px{};
  for (int i = 0; i < 3; ++i)
    px[std::size_t(i)] = p[std::size_t(3 * i)] * x[0] + p[std::size_t(3 * i + 1)] * x[1] +
                         p[std::size_t(3 * i + 2)] * x[2];
  const double den = lambda + x[0] * px[0] + x[1] * px[1] + x[2] * px[2];
  const double e = y - (x[0] * theta[0] + x[1] * theta[1] + x[2] * theta[2]);
  for (int i = 0; i < 3; ++i) theta[std::size_t(i)] += px[std::size_t(i)] / den * e;
  // P = (P - Px Px' / den) / lambda; P stays symmetric.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      p[std::size_t(3 * i + j)] =
          (p[std::size_t(3 * i + j)] - px[std::size_t(i)] * px[std::size_t(j)] / den) / lambda;
  return lambda * e * e / den;
}

}  // namespace

std::string_view to_string(SoilField field) {
  switch (field) {
    case SoilField::kUnitWeight: return "unit_weight_n_per_m3";
    case SoilField::kCohesion: return "cohesion_pa";
    case SoilField::kAdhesion: return "adhesion_pa";
    case SoilField::kInternalFriction: return "internal_friction_deg";
    case SoilField::kSoilToolFriction: return "soil_tool_friction_deg";
  }
  return "?";
}

double field_value(const SoilMaterial& m, SoilField field) {
  switch (field) {
    case SoilField::kUnitWeight: return m.unit_weight_n_per_m3;
    case SoilField::kCohesion: return m.cohesion_pa;
    case SoilField::kAdhesion: return m.adhesion_pa;
    case SoilField::kInternalFriction: return m.internal_friction_deg;
    case SoilField::kSoilToolFriction: return m.soil_tool_friction_deg;
  }
  return 0.0;
}

StepSample soil_sample(const ToolForce& force, const ToolMotion& motion, double rake_deg) noexcept {
  StepSample out;
  const Vec3 v = motion.velocity_m_per_s;
  const double speed = std::hypot(v.x, v.z);
  if (!(speed >= kRestSpeed_m_per_s) || !(force.engaged_width_m > 0.0) ||
      !(force.cut_depth_m > 0.0))
    return out;
  // The soil's force on the blade, cutting and pile: -H u - V Y.
  const Vec3 f = force.cutting_n + force.surcharge_n;
  out.sample.width_m = force.engaged_width_m;
  out.sample.depth_m = force.cut_depth_m;
  out.sample.pile_m = force.pile_m;
  out.sample.rake_deg = rake_deg;
  out.sample.horizontal_n = -(f.x * v.x + f.z * v.z) / speed;
  out.sample.vertical_n = -f.y;
  out.valid = finite_all(out.sample);
  return out;
}

std::string validate(const SoilEstimatorSettings& s) {
  if (!(s.forgetting_per_sample > 0.0 && s.forgetting_per_sample <= 1.0))
    return must_be("forgetting_per_sample", "in (0, 1]", s.forgetting_per_sample);
  if (!(s.phi_min_deg >= 0.0 && s.phi_min_deg < 89.0))
    return must_be("phi_min_deg", "in [0, 89)", s.phi_min_deg);
  if (!(s.phi_max_deg > s.phi_min_deg && s.phi_max_deg < 89.0))
    return must_be("phi_max_deg", "in (phi_min_deg, 89)", s.phi_max_deg);
  if (!(s.angle_step_deg >= 0.5 && s.angle_step_deg <= 20.0))
    return must_be("angle_step_deg", "in [0.5, 20]", s.angle_step_deg);
  if (std::string e = validate(s.prior); !e.empty()) return "prior." + e;
  for (double sd : s.prior_sd)
    if (!(std::isfinite(sd) && sd > 0.0)) return must_be("prior_sd", "finite and > 0", sd);
  if (!(std::isfinite(s.force_noise_n) && s.force_noise_n > 0.0))
    return must_be("force_noise_n", "finite and > 0", s.force_noise_n);
  for (double r : s.resolution)
    if (!(std::isfinite(r) && r > 0.0)) return must_be("resolution", "finite and > 0", r);
  return {};
}

SoilEstimator::SoilEstimator(const SoilEstimatorSettings& settings) : settings_(settings) {
  if (std::string e = validate(settings_); !e.empty()) throw InputError("soil estimator: " + e);
  // The grid: phi from phi_min in steps, delta from 0 to phi in the same steps.
  const double step = settings_.angle_step_deg;
  phi_steps_ = int(std::floor((settings_.phi_max_deg - settings_.phi_min_deg) / step + 1e-9)) + 1;
  for (int i = 0; i < phi_steps_; ++i) {
    row_start_.push_back(int(candidates_.size()));
    const double phi = settings_.phi_min_deg + i * step;
    for (int j = 0; j * step <= phi + 1e-9; ++j) {
      Candidate c;
      c.phi_deg = phi;
      c.delta_deg = j * step;
      candidates_.push_back(c);
    }
  }
  row_start_.push_back(int(candidates_.size()));
  // The cuts remembered for the information matrix: three memories of the
  // forgetting (their weight beyond is under 5 %), at most 512.
  const double memory = 1.0 / std::max(1.0 - settings_.forgetting_per_sample, 1e-6);
  memory_.resize(std::size_t(std::clamp(3.0 * memory, 16.0, 512.0)));
  reset();
}

int SoilEstimator::index(int phi_i, int delta_i) const {
  if (phi_i < 0 || phi_i >= phi_steps_ || delta_i < 0) return -1;
  const int k = row_start_[std::size_t(phi_i)] + delta_i;
  return k < row_start_[std::size_t(phi_i) + 1] ? k : -1;
}

void SoilEstimator::restart_memory() {
  for (Candidate& c : candidates_) {
    c.p = {};
    for (int i = 0; i < 3; ++i) {
      const double sd = settings_.prior_sd[std::size_t(i)] * kToKilo;
      c.p[std::size_t(4 * i)] = sd * sd;
    }
    c.cost = std::isfinite(c.cost) ? 0.0 : c.cost;
    c.weight = 0.0;
  }
  since_reset_ = 0;
  surprises_ = 0;
  memory_size_ = 0;
  memory_next_ = 0;
}

void SoilEstimator::reset() {
  const SoilMaterial& m = settings_.prior;
  for (Candidate& c : candidates_) {
    c.theta = {m.unit_weight_n_per_m3 * kToKilo, m.cohesion_pa * kToKilo, m.adhesion_pa * kToKilo};
    c.cost = 0.0;
    c.beta_rad = 0.0;
    c.last_error = 0.0;
  }
  restart_memory();
  best_ = -1;
  pending_ = false;
  next_ = 0;
  estimate_ = {};
  estimate_.material = settings_.prior;
  for (int f = 0; f < kSoilFieldCount; ++f) estimate_.sd[std::size_t(f)] = 0.0;
}

bool SoilEstimator::add(const SoilSample& sample) {
  if (!begin(sample)) return false;
  advance(int(candidates_.size()));
  return true;
}

bool SoilEstimator::begin(const SoilSample& sample) {
  if (pending_) return false;
  if (!finite_all(sample) || !(sample.width_m > 0.0) || !(sample.depth_m > 0.0) ||
      !(sample.pile_m >= 0.0) || !(sample.rake_deg > 0.0 && sample.rake_deg < 180.0))
    return false;
  sample_ = sample;
  pending_ = true;
  next_ = 0;
  return true;
}

bool SoilEstimator::advance(int count) {
  if (!pending_) return false;
  const std::size_t end = std::min(candidates_.size(), next_ + std::size_t(std::max(count, 0)));
  for (; next_ < end; ++next_) take(candidates_[next_], sample_);
  if (next_ < candidates_.size()) return false;
  pending_ = false;
  finish_sample();
  return true;
}

// beta*, the failure-plane angle that minimises P for the candidate's
// material (earthmoving.hpp): a golden-section search to 1e-7 rad around
// the candidate's previous beta* (the cut changes little between samples),
// or the whole range by earthmoving_force's own search on its first sample
// or when the previous one sits at the bracket's end. P is flat at its
// minimum, so 1e-7 rad changes the factors' P by far less than rounding.
double SoilEstimator::failure_angle(Candidate& c, const EarthmovingParams& params,
                                    const SoilSample& s, double q) const {
  const BetaRange range = earthmoving_beta_range(params);
  constexpr double kEdge = 1e-4, kBracket = 0.08;
  const double lo_all = range.lo_rad + kEdge;
  const double hi_all = range.hi_rad >= 1.5707963267948966 ? range.hi_rad : range.hi_rad - kEdge;
  if (c.beta_rad > 0.0) {
    double a = std::max(lo_all, c.beta_rad - kBracket), b = std::min(hi_all, c.beta_rad + kBracket);
    auto total = [&](double beta) {
      return earthmoving_total_n(params, s.width_m, s.depth_m, beta, q);
    };
    constexpr double kInvPhi = 0.6180339887498949;
    double x1 = b - kInvPhi * (b - a), x2 = a + kInvPhi * (b - a);
    double f1 = total(x1), f2 = total(x2);
    while (b - a > 1e-7) {
      if (f1 <= f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - kInvPhi * (b - a);
        f1 = total(x1);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + kInvPhi * (b - a);
        f2 = total(x2);
      }
    }
    const double beta = 0.5 * (a + b);
    // Inside the bracket (or at the range's own end): the minimum.
    const bool at_bracket_end = (beta - (c.beta_rad - kBracket) < 1e-5 && beta - lo_all > 1e-5) ||
                                ((c.beta_rad + kBracket) - beta < 1e-5 && hi_all - beta > 1e-5);
    if (!at_bracket_end) {
      c.beta_rad = beta;
      return beta;
    }
  }
  c.beta_rad = earthmoving_force(params, s.width_m, s.depth_m, q).beta_rad;
  return c.beta_rad;
}

// One sample into one candidate: the factors at the beta* of the
// candidate's own estimate (clipped to physical values), then the H and V
// equations, linear in (gamma, c, c_a).
void SoilEstimator::take(Candidate& c, const SoilSample& s) const {
  EarthmovingParams params;
  params.rake_angle_deg = s.rake_deg;
  params.side_failure = true;
  params.soil.internal_friction_deg = c.phi_deg;
  params.soil.soil_tool_friction_deg = c.delta_deg;
  // A pair that leaves no failure wedge at this rake cannot have made the sample.
  if (!(s.rake_deg + c.phi_deg + c.delta_deg <= 179.0)) {
    c.cost = HUGE_VAL;
    return;
  }
  params.soil.unit_weight_n_per_m3 =
      std::max(c.theta[0], 0.01 * settings_.prior.unit_weight_n_per_m3 * kToKilo) / kToKilo;
  params.soil.cohesion_pa = std::max(c.theta[1], 0.0) / kToKilo;
  params.soil.adhesion_pa = std::max(c.theta[2], 0.0) / kToKilo;
  const double q = params.soil.unit_weight_n_per_m3 * s.pile_m;
  const EarthmovingFactors n =
      earthmoving_factors(params, failure_angle(c, params, s, q), s.width_m, s.depth_m);
  const double alpha = radians(s.rake_deg), delta = radians(c.delta_deg);
  const double sin_ad = std::sin(alpha + delta), cos_ad = std::cos(alpha + delta);
  const double cot_a = std::cos(alpha) / std::sin(alpha);
  const double w = s.width_m, d = s.depth_m;
  // P per unit of each parameter, m^3 and m^2 (kN per kN/m^3 and per kPa).
  const double p_gamma = w * (d * d * n.n_gamma + s.pile_m * d * n.n_q);
  const double p_c = w * d * n.n_c;
  const double p_a = w * d * n.n_a;
  const std::array<double, 3> xh{p_gamma * sin_ad, p_c * sin_ad, p_a * sin_ad + d * w * cot_a};
  const std::array<double, 3> xv{p_gamma * cos_ad, p_c * cos_ad, p_a * cos_ad - d * w};
  const double lambda = settings_.forgetting_per_sample;
  // The a-priori error of the horizontal force: how far this candidate's
  // fit so far was from the sample (the change-of-soil test's).
  c.last_error = s.horizontal_n * kToKilo -
                 (xh[0] * c.theta[0] + xh[1] * c.theta[1] + xh[2] * c.theta[2]);
  // Forgetting once per sample: the first equation carries it.
  c.cost = lambda * c.cost + rls_update(c.theta, c.p, xh, s.horizontal_n * kToKilo, lambda);
  c.cost += rls_update(c.theta, c.p, xv, s.vertical_n * kToKilo, 1.0);
  c.weight = lambda * c.weight + 2.0;
}

// The estimate from the candidates: the best admissible pair and its fit,
// with the uncertainties of the profile likelihood (every pair whose cost
// is within one residual variance of the best's lies inside the one-sigma
// region: its angles and its fit are as likely) and of the linear fit.
void SoilEstimator::finish_sample() {
  for (std::size_t k = 0; k < memory_size_; ++k) ++memory_[k].age;
  ++estimate_.samples;
  ++since_reset_;
  // A change of soil: the estimate's own candidate missed kSurprises more
  // samples than it met (a count up on a miss, down on a hit) by more than kSurpriseFraction of the force (and by more than
  // 4 times its residuals' RMS), once the memory had kSettled samples. Then
  // the memory restarts (the covariance back to the prior's, the costs to
  // zero, the fits kept as the starting point): covariance resetting, so
  // that the new soil is learnt at the rate of a fresh start and not after
  // the old samples have been forgotten.
  constexpr double kSurpriseFraction = 0.08;
  constexpr int kSurprises = 3;
  constexpr std::int64_t kSettled = 10;
  if (best_ >= 0 && since_reset_ > kSettled) {
    // Against the residuals the fit had before the misses began (each
    // miss raises them).
    const Candidate& was = candidates_[std::size_t(best_)];
    if (surprises_ == 0) calm_rms_n_ = estimate_.residual_rms_n;
    const double sigma = std::max(calm_rms_n_, settings_.force_noise_n) * kToKilo;
    const double e = std::fabs(was.last_error);
    if (e > kSurpriseFraction * std::fabs(sample_.horizontal_n * kToKilo) && e > 4.0 * sigma)
      ++surprises_;
    else
      surprises_ = std::max(surprises_ - 1, 0);
    if (surprises_ >= kSurprises) {
      restart_memory();
      ++estimate_.restarts;
    }
  }
  // Until the memory holds kFirst samples (six equations for three linear
  // parameters and the pair of angles) every candidate fits them: the
  // estimate stays where it was (the prior at the start).
  constexpr std::int64_t kFirst = 3;
  if (since_reset_ < kFirst) return;
  // The first samples' regressors were taken at the failure angle of each
  // candidate's unsettled fit (its prior): their residuals say how far the
  // prior was, not how well the candidate fits. The costs start afresh
  // once the fits have settled (kFirst samples).
  if (since_reset_ == kFirst)
    for (Candidate& c : candidates_)
      if (std::isfinite(c.cost)) {
        c.cost = 0.0;
        c.weight = 0.0;
      }
  estimate_.known = true;

  // The residual variance, kN^2, of the best fit, with the sensor's floor.
  std::size_t best = 0;
  for (std::size_t k = 1; k < candidates_.size(); ++k)
    if (candidates_[k].cost < candidates_[best].cost) best = k;
  const Candidate& b0 = candidates_[best];
  const double dof = std::max(b0.weight - 5.0, 1.0);
  const double noise_kn = settings_.force_noise_n * kToKilo;
  const double sigma2 = std::max(b0.cost / dof, noise_kn * noise_kn);
  const double j_min = b0.cost;

  // Admissible: no linear parameter more than two of its standard
  // deviations below zero (a negative weight or cohesion fits a cut only
  // through a null direction the cuts do not see, and clipped it would
  // predict another force). The estimate is the admissible pair of least
  // cost; the best overall when none is.
  auto admissible = [&](const Candidate& c) {
    for (int i = 0; i < 3; ++i)
      if (c.theta[std::size_t(i)] < -2.0 * std::sqrt(sigma2 * c.p[std::size_t(4 * i)])) return false;
    return true;
  };
  int chosen = -1;
  for (std::size_t k = 0; k < candidates_.size(); ++k)
    if (std::isfinite(candidates_[k].cost) && admissible(candidates_[k]) &&
        (chosen < 0 || candidates_[k].cost < candidates_[std::size_t(chosen)].cost))
      chosen = int(k);
  if (chosen < 0) chosen = int(best);
  best_ = chosen;
  const Candidate& b = candidates_[std::size_t(chosen)];
  // The sample into the memory of cuts, with the failure angle the chosen
  // pair found for it.
  Remembered& r = memory_[memory_next_];
  r.sample = sample_;
  r.beta_rad = b.beta_rad;
  r.age = 0;
  memory_next_ = (memory_next_ + 1) % memory_.size();
  memory_size_ = std::min(memory_size_ + 1, memory_.size());
  estimate_.residual_rms_n = std::sqrt(std::max(b.cost, 0.0) / std::max(b.weight, 1.0)) / kToKilo;

  // The one-sigma region of the profile: the largest distance of any pair
  // (and of its fit) with a cost within sigma^2 of the least, from the
  // estimate's; and the grid's own resolution: the pair of least cost is
  // not always the nearest to the truth, but lies within a step of it
  // (tested on the presets), so a uniform error over +-1 step (step^2 / 3)
  // for the angles and over +-1 change of the fit between neighbouring
  // pairs for the linear parameters.
  const double step = settings_.angle_step_deg;
  std::array<double, kSoilFieldCount> spread{};
  std::array<double, 3> neighbour_change{};
  for (std::size_t k = 0; k < candidates_.size(); ++k) {
    const Candidate& c = candidates_[k];
    if (!std::isfinite(c.cost)) continue;
    const double dphi = c.phi_deg - b.phi_deg, ddelta = c.delta_deg - b.delta_deg;
    if (c.cost - j_min <= sigma2) {
      for (int i = 0; i < 3; ++i)
        spread[std::size_t(i)] =
            std::max(spread[std::size_t(i)], std::fabs(c.theta[std::size_t(i)] - b.theta[std::size_t(i)]));
      spread[3] = std::max(spread[3], std::fabs(dphi));
      spread[4] = std::max(spread[4], std::fabs(ddelta));
    }
    if (std::fabs(dphi) + std::fabs(ddelta) <= step * 1.000001 && k != std::size_t(chosen))
      for (int i = 0; i < 3; ++i)
        neighbour_change[std::size_t(i)] = std::max(
            neighbour_change[std::size_t(i)], std::fabs(c.theta[std::size_t(i)] - b.theta[std::size_t(i)]));
  }
  std::array<double, kSoilFieldCount> var{};
  for (int i = 0; i < 3; ++i)
    var[std::size_t(i)] = sigma2 * b.p[std::size_t(4 * i)] +
                          spread[std::size_t(i)] * spread[std::size_t(i)] +
                          neighbour_change[std::size_t(i)] * neighbour_change[std::size_t(i)] / 3.0;
  var[3] = spread[3] * spread[3] + step * step / 3.0;
  var[4] = spread[4] * spread[4] + step * step / 3.0;

  // The information matrix of all five parameters over the samples in
  // memory (forgetting-weighted), at the estimate: a parameter the cuts do
  // not tell apart from the others (one depth: the weight's d^2 against the
  // cohesion's d; one rake and no adhesion: delta against c_a) has an
  // unbounded variance there, whatever the profile says.
  const std::array<double, kSoilFieldCount> fisher_var = information_variance(b, sigma2);
  for (int f = 0; f < kSoilFieldCount; ++f)
    var[std::size_t(f)] = std::max(var[std::size_t(f)], fisher_var[std::size_t(f)]);

  SoilMaterial& m = estimate_.material;
  m = settings_.prior;
  m.unit_weight_n_per_m3 =
      std::max(b.theta[0] / kToKilo, 0.01 * settings_.prior.unit_weight_n_per_m3);
  m.cohesion_pa = std::max(b.theta[1] / kToKilo, 0.0);
  m.adhesion_pa = std::max(b.theta[2] / kToKilo, 0.0);
  m.internal_friction_deg = b.phi_deg;
  m.soil_tool_friction_deg = b.delta_deg;
  for (int i = 0; i < 3; ++i) estimate_.sd[std::size_t(i)] = std::sqrt(var[std::size_t(i)]) / kToKilo;
  estimate_.sd[3] = std::sqrt(var[3]);
  estimate_.sd[4] = std::sqrt(var[4]);
  estimate_.identifiable = 0;
  for (int f = 0; f < kSoilFieldCount; ++f)
    if (estimate_.sd[std::size_t(f)] <= settings_.resolution[std::size_t(f)])
      estimate_.identifiable |= 1u << f;
}


// The model's H and V (kN) for a remembered cut at the given parameters
// (theta in kN/m^3 and kPa, angles in degrees) at the cut's failure angle:
// at beta* the force is stationary in beta, so its derivatives in the
// parameters at a fixed beta are the derivatives of the force itself.
static void model_hv(const SoilSample& s, double beta, const std::array<double, 5>& x, double& h,
                     double& v) {
  EarthmovingParams params;
  params.rake_angle_deg = s.rake_deg;
  params.side_failure = true;
  params.soil.internal_friction_deg = x[3];
  params.soil.soil_tool_friction_deg = x[4];
  const EarthmovingFactors n = earthmoving_factors(params, beta, s.width_m, s.depth_m);
  const double alpha = radians(s.rake_deg), delta = radians(x[4]);
  const double w = s.width_m, d = s.depth_m;
  const double p = w * (x[0] * (d * d * n.n_gamma + s.pile_m * d * n.n_q) + x[1] * d * n.n_c +
                        x[2] * d * n.n_a);
  h = p * std::sin(alpha + delta) + x[2] * d * w * std::cos(alpha) / std::sin(alpha);
  v = p * std::cos(alpha + delta) - x[2] * d * w;
}

std::array<double, kSoilFieldCount> SoilEstimator::information_variance(const Candidate& b,
                                                                        double sigma2) const {
  std::array<double, kSoilFieldCount> out{};
  constexpr double kUnbounded = 1e12;  // (parameter units)^2: nothing known
  out.fill(kUnbounded);
  if (memory_size_ == 0) return out;
  const std::array<double, 5> x0{b.theta[0], b.theta[1], b.theta[2], b.phi_deg, b.delta_deg};
  constexpr double kAngleStep = 0.01;  // degrees, for the angles' derivatives
  double f[5][5] = {};
  const double lambda = settings_.forgetting_per_sample;
  for (std::size_t k = 0; k < memory_size_; ++k) {
    const Remembered& r = memory_[k];
    const double weight = std::pow(lambda, double(r.age));
    double jh[5], jv[5], h0, v0;
    model_hv(r.sample, r.beta_rad, x0, h0, v0);
    for (int i = 0; i < 5; ++i) {
      std::array<double, 5> x = x0;
      const double dx = i < 3 ? 1.0 : kAngleStep;  // linear: any step is exact
      x[std::size_t(i)] += dx;
      double h, v;
      model_hv(r.sample, r.beta_rad, x, h, v);
      jh[i] = (h - h0) / dx;
      jv[i] = (v - v0) / dx;
    }
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) f[i][j] += weight * (jh[i] * jh[j] + jv[i] * jv[j]);
  }
  // Invert by Gauss-Jordan with partial pivoting; a pivot below 1e-10 of
  // the largest diagonal is a direction the cuts do not see.
  double inv[5][5] = {};
  double a[5][5];
  double scale = 0.0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) a[i][j] = f[i][j];
    inv[i][i] = 1.0;
    scale = std::max(scale, f[i][i]);
  }
  if (!(scale > 0.0)) return out;
  for (int col = 0; col < 5; ++col) {
    int piv = col;
    for (int r = col + 1; r < 5; ++r)
      if (std::fabs(a[r][col]) > std::fabs(a[piv][col])) piv = r;
    if (!(std::fabs(a[piv][col]) > 1e-10 * scale)) return out;
    for (int k = 0; k < 5; ++k) {
      std::swap(a[col][k], a[piv][k]);
      std::swap(inv[col][k], inv[piv][k]);
    }
    const double d = a[col][col];
    for (int k = 0; k < 5; ++k) {
      a[col][k] /= d;
      inv[col][k] /= d;
    }
    for (int r = 0; r < 5; ++r)
      if (r != col) {
        const double m = a[r][col];
        for (int k = 0; k < 5; ++k) {
          a[r][k] -= m * a[col][k];
          inv[r][k] -= m * inv[col][k];
        }
      }
  }
  for (int i = 0; i < 5; ++i) {
    const double var = sigma2 * inv[i][i];
    if (!(var >= 0.0) || !std::isfinite(var)) continue;
    // Back to N/m^3 and Pa for the linear ones (the estimate's sd units
    // are applied by the caller: kN-based here).
    out[std::size_t(i)] = std::min(var, kUnbounded);
  }
  return out;
}

}  // namespace terracut
