// Online estimation of a soil's material from the physical cutting force.
// See soil_estimator.hpp; the method and its sources: docs/teleoperation.md
// ("The soil estimate").
#include "terracut/core/soil_estimator.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/penetration.hpp"

namespace terracut {

namespace {

// The model's H and V for a remembered cut at parameters x (defined below).
void model_hv(const SoilSample& s, double beta, const std::array<double, 5>& x, double& h,
              double& v, double& p);

// The linear parameters are fitted in kN/m^3 and kPa against forces in kN,
// so that the covariance and the residuals stay near unity.
constexpr double kToKilo = 1e-3;

bool finite_all(const SoilSample& s) {
  return std::isfinite(s.width_m) && std::isfinite(s.depth_m) && std::isfinite(s.pile_m) &&
         std::isfinite(s.rake_deg) && std::isfinite(s.horizontal_n) && std::isfinite(s.vertical_n) &&
         std::isfinite(s.penetration_n) && std::isfinite(s.embedment_depth_m) &&
         std::isfinite(s.embedded_length_m) && std::isfinite(s.edge_thickness_m);
}

// The penetration force (kN) of a sample's edge at a material of (gamma
// kN/m^3, c kPa, c_a kPa) and angles (degrees): the model itself
// (penetration.hpp), down (tip and faces) or up (faces).
double penetration_kn(const SoilSample& s, double gamma, double c, double c_a, double phi,
                      double delta) {
  SoilMaterial m;
  m.unit_weight_n_per_m3 = gamma / kToKilo;
  m.cohesion_pa = c / kToKilo;
  m.adhesion_pa = c_a / kToKilo;
  m.internal_friction_deg = phi;
  m.soil_tool_friction_deg = delta;
  const PenetrationResult r =
      penetration_resistance(m, s.edge_thickness_m, s.embedded_length_m, s.embedment_depth_m,
                             m.unit_weight_n_per_m3 * s.pile_m);
  return (s.penetration_direction < 0 ? r.down_n() : r.up_n()) * kToKilo;
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

StepSample soil_sample(const ToolForce& force, const ToolMotion& motion, double rake_deg,
                       double edge_thickness_m) noexcept {
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
  // The edge moving down or up in the soil: the penetration force too.
  if (std::fabs(v.y) >= kRestSpeed_m_per_s && force.embedment_depth_m > 0.0 &&
      force.embedded_length_m > 0.0 && edge_thickness_m > 0.0) {
    out.sample.penetration_direction = v.y < 0.0 ? -1 : 1;
    out.sample.penetration_n = std::fabs(force.penetration_n.y);
    out.sample.embedment_depth_m = force.embedment_depth_m;
    out.sample.embedded_length_m = force.embedded_length_m;
    out.sample.edge_thickness_m = edge_thickness_m;
  }
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
  // The cuts remembered for the refinement and the information matrix:
  // three memories of the forgetting (their weight beyond is under 5 %), at
  // most 256 (the refinement's cost on the tick that finishes a sample).
  const double memory = 1.0 / std::max(1.0 - settings_.forgetting_per_sample, 1e-6);
  memory_.resize(std::size_t(std::clamp(3.0 * memory, 16.0, 256.0)));
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
  refined_before_ = false;
}

void SoilEstimator::reset() {
  const SoilMaterial& m = settings_.prior;
  for (Candidate& c : candidates_) {
    c.theta = {m.unit_weight_n_per_m3 * kToKilo, m.cohesion_pa * kToKilo, m.adhesion_pa * kToKilo};
    c.cost = 0.0;
    c.beta_rad = 0.0;
  }
  restart_memory();
  calm_rms_n_ = 0.0;
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
  if (sample.penetration_direction != 0 &&
      (!(sample.penetration_n >= 0.0) || !(sample.embedment_depth_m > 0.0) ||
       !(sample.embedded_length_m > 0.0) || !(sample.edge_thickness_m > 0.0)))
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

namespace {

// beta*, the failure-plane angle that minimises P for a material
// (earthmoving.hpp): a golden-section search to 1e-7 rad around a previous
// beta* (the cut and the material change little between calls), or the
// whole range by earthmoving_force's own search when there is none
// (previous <= 0) or the minimum sits at the bracket's end. P is flat at
// its minimum, so 1e-7 rad changes it by far less than rounding.
double beta_star(const EarthmovingParams& params, const SoilSample& s, double q, double previous) {
  const BetaRange range = earthmoving_beta_range(params);
  constexpr double kEdge = 1e-4, kBracket = 0.08;
  const double lo_all = range.lo_rad + kEdge;
  const double hi_all = range.hi_rad >= 1.5707963267948966 ? range.hi_rad : range.hi_rad - kEdge;
  if (previous > 0.0) {
    double a = std::max(lo_all, previous - kBracket), b = std::min(hi_all, previous + kBracket);
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
    const bool at_bracket_end = (beta - (previous - kBracket) < 1e-5 && beta - lo_all > 1e-5) ||
                                ((previous + kBracket) - beta < 1e-5 && hi_all - beta > 1e-5);
    if (!at_bracket_end) return beta;
  }
  return earthmoving_force(params, s.width_m, s.depth_m, q).beta_rad;
}

}  // namespace

double SoilEstimator::failure_angle(Candidate& c, const EarthmovingParams& params,
                                    const SoilSample& s, double q) const {
  c.beta_rad = beta_star(params, s, q, c.beta_rad);
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
  // Forgetting once per sample: the first equation carries it.
  c.cost = lambda * c.cost + rls_update(c.theta, c.p, xh, s.horizontal_n * kToKilo, lambda);
  c.cost += rls_update(c.theta, c.p, xv, s.vertical_n * kToKilo, 1.0);
  c.weight = lambda * c.weight + 2.0;
  // The penetration force, linear in (gamma, c, c_a) at the pair's angles:
  // its regressors are the model's force at each unit parameter.
  if (s.penetration_direction != 0) {
    const std::array<double, 3> xp{penetration_kn(s, 1.0, 0.0, 0.0, c.phi_deg, c.delta_deg),
                                   penetration_kn(s, 0.0, 1.0, 0.0, c.phi_deg, c.delta_deg),
                                   penetration_kn(s, 0.0, 0.0, 1.0, c.phi_deg, c.delta_deg)};
    c.cost += rls_update(c.theta, c.p, xp, s.penetration_n * kToKilo, 1.0);
    c.weight += 1.0;
  }
}

// The estimate from the candidates: the best admissible pair and its fit,
// with the uncertainties of the profile likelihood (every pair whose cost
// is within one residual variance of the best's lies inside the one-sigma
// region: its angles and its fit are as likely) and of the linear fit.
void SoilEstimator::finish_sample() {
  for (std::size_t k = 0; k < memory_size_; ++k) ++memory_[k].age;
  ++estimate_.samples;
  ++since_reset_;
  // A change of soil is a run of samples the estimate mispredicts that no
  // one material fits together with the remembered ones. A miss is a
  // horizontal force more than kSurpriseFraction of the measured one and
  // more than 4 times the fit's residual RMS (before the misses began) away
  // from the estimate's (counted up on a miss, down on a hit, once the
  // memory had kSettled samples). At kSurprises the refit below decides: if
  // the newest samples are fitted as well as the old ones were, they only
  // showed what the old cuts had left loose (a depth never cut before), and
  // the memory stays; if not, the soil changed and the memory restarts (the
  // covariance back to the prior's, the costs to zero, the fits kept as the
  // starting point): covariance resetting, so that the new soil is learnt
  // at the rate of a fresh start and not after the old samples have been
  // forgotten.
  constexpr double kSurpriseFraction = 0.08;
  constexpr int kSurprises = 3;
  constexpr std::int64_t kSettled = 10;
  bool judge_change = false;
  if (estimate_.known && since_reset_ > kSettled) {
    if (surprises_ == 0) calm_rms_n_ = estimate_.residual_rms_n;
    EarthmovingParams p;
    p.soil = estimate_.material;
    p.rake_angle_deg = sample_.rake_deg;
    const double predicted =
        earthmoving_force(p, sample_.width_m, sample_.depth_m,
                          p.soil.unit_weight_n_per_m3 * sample_.pile_m).horizontal_n;
    const double e = std::fabs(predicted - sample_.horizontal_n);
    const double floor_n = 4.0 * std::max(calm_rms_n_, settings_.force_noise_n);
    if (e > kSurpriseFraction * std::fabs(sample_.horizontal_n) && e > floor_n)
      ++surprises_;
    else
      surprises_ = std::max(surprises_ - 1, 0);
    judge_change = surprises_ >= kSurprises;
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
  const Candidate& b = candidates_[std::size_t(chosen)];
  // The sample into the memory of cuts, with the failure angle the chosen
  // pair found for it.
  Remembered& r = memory_[memory_next_];
  r.sample = sample_;
  r.beta_rad = b.beta_rad;
  if (refined_before_) {
    // Its failure angle at the estimate the refinement starts from.
    EarthmovingParams p;
    p.rake_angle_deg = sample_.rake_deg;
    p.soil.unit_weight_n_per_m3 = previous_x_[0] / kToKilo;
    p.soil.cohesion_pa = previous_x_[1] / kToKilo;
    p.soil.adhesion_pa = previous_x_[2] / kToKilo;
    p.soil.internal_friction_deg = previous_x_[3];
    p.soil.soil_tool_friction_deg = previous_x_[4];
    r.beta_rad = beta_star(p, sample_, p.soil.unit_weight_n_per_m3 * sample_.pile_m, r.beta_rad);
  }
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
  // The estimate is made anew every kRefineEvery samples (the refinement
  // below costs about a millisecond over 256 remembered cuts: once in five
  // samples it fits the ticks of a 1 kHz loop on average, and a station
  // sends its estimate every sensing period anyway), and whenever a run of
  // misses is to be judged; in between the samples go on into the pairs and
  // the memory.
  constexpr std::int64_t kRefineEvery = 5;
  if (refined_before_ && !judge_change && estimate_.samples % kRefineEvery != 0) return;

  // The grid's answer: the pair's own fit, with the profile's spread and
  // the grid's resolution (the pair of least cost lies within a step of
  // the truth) as its uncertainty.
  std::array<double, kSoilFieldCount> x{b.theta[0], b.theta[1], b.theta[2], b.phi_deg, b.delta_deg};
  std::array<double, kSoilFieldCount> var{};
  for (int i = 0; i < 3; ++i)
    var[std::size_t(i)] = sigma2 * b.p[std::size_t(4 * i)] +
                          spread[std::size_t(i)] * spread[std::size_t(i)] +
                          neighbour_change[std::size_t(i)] * neighbour_change[std::size_t(i)] / 3.0;
  var[3] = spread[3] * spread[3] + step * step / 3.0;
  var[4] = spread[4] * spread[4] + step * step / 3.0;

  // Refined between the grid's points: Gauss-Newton (Levenberg-Marquardt)
  // on all five parameters over the cuts in memory, from the pair's fit,
  // and the uncertainty of the information matrix there (a parameter the
  // cuts do not tell apart from the others, as the weight's d^2 from the
  // cohesion's d at one depth, has an unbounded variance).
  // Started from the previous estimate (the grid's best pair can jump
  // where the cuts leave the angles loose, as a blade leaving the soil
  // does), and every other time (or without a previous one) from the
  // grid's answer too, which finds another valley when there is one; the
  // better fit is kept.
  constexpr std::int64_t kGridEvery = 2 * kRefineEvery;
  Refined fit;
  if (refined_before_) fit = refine(previous_x_, false);
  if (!refined_before_ || estimate_.samples % kGridEvery == 0) {
    const Refined grid = refine(x, true);
    if (grid.ok && (!fit.ok || grid.cost < fit.cost)) fit = grid;
  }
  if (fit.ok) {
    previous_x_ = fit.x;
    refined_before_ = true;
    x = fit.x;
    var = fit.var;
    estimate_.residual_rms_n = std::sqrt(fit.cost / std::max(fit.weight, 1.0)) / kToKilo;
  }

  SoilMaterial& m = estimate_.material;
  m = settings_.prior;
  m.unit_weight_n_per_m3 = std::max(x[0] / kToKilo, 0.01 * settings_.prior.unit_weight_n_per_m3);
  m.cohesion_pa = std::max(x[1] / kToKilo, 0.0);
  m.adhesion_pa = std::max(x[2] / kToKilo, 0.0);
  m.internal_friction_deg = x[3];
  m.soil_tool_friction_deg = x[4];
  for (int i = 0; i < 3; ++i) estimate_.sd[std::size_t(i)] = std::sqrt(var[std::size_t(i)]) / kToKilo;
  estimate_.sd[3] = std::sqrt(var[3]);
  estimate_.sd[4] = std::sqrt(var[4]);
  estimate_.identifiable = 0;
  for (int f = 0; f < kSoilFieldCount; ++f)
    if (estimate_.sd[std::size_t(f)] <= settings_.resolution[std::size_t(f)])
      estimate_.identifiable |= 1u << f;

  // The run of misses judged: the newest kSurprises + 2 samples' residuals
  // under the refit against the fit's residuals before the misses.
  if (judge_change) {
    surprises_ = 0;
    const double newest_rms_n = fit.ok ? newest_residual_rms_n(fit.x, kSurprises + 2) : HUGE_VAL;
    if (newest_rms_n > 4.0 * std::max(calm_rms_n_, settings_.force_noise_n)) {
      restart_memory();
      ++estimate_.restarts;
    }
  }
}

double SoilEstimator::newest_residual_rms_n(const std::array<double, kSoilFieldCount>& x,
                                            std::int64_t newest) const {
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < memory_size_; ++k) {
    const Remembered& r = memory_[k];
    if (r.age >= newest) continue;
    double h, v, p;
    model_hv(r.sample, r.beta_rad, x, h, v, p);
    const double eh = r.sample.horizontal_n * kToKilo - h, ev = r.sample.vertical_n * kToKilo - v;
    sum += eh * eh + ev * ev;
    n += 2;
    if (r.sample.penetration_direction != 0) {
      const double ep = r.sample.penetration_n * kToKilo - p;
      sum += ep * ep;
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum / n) / kToKilo : 0.0;
}

namespace {

// The model's H and V (kN) for a remembered cut at the given parameters
// (theta in kN/m^3 and kPa, angles in degrees) at the cut's failure angle:
// at beta* the force is stationary in beta, so its derivatives in the
// parameters at a fixed beta are the derivatives of the force itself.
void model_hv(const SoilSample& s, double beta, const std::array<double, 5>& x, double& h,
              double& v, double& p) {
  EarthmovingParams params;
  params.rake_angle_deg = s.rake_deg;
  params.side_failure = true;
  params.soil.internal_friction_deg = x[3];
  params.soil.soil_tool_friction_deg = x[4];
  const EarthmovingFactors n = earthmoving_factors(params, beta, s.width_m, s.depth_m);
  const double alpha = radians(s.rake_deg), delta = radians(x[4]);
  const double w = s.width_m, d = s.depth_m;
  const double p_face = w * (x[0] * (d * d * n.n_gamma + s.pile_m * d * n.n_q) + x[1] * d * n.n_c +
                             x[2] * d * n.n_a);
  h = p_face * std::sin(alpha + delta) + x[2] * d * w * std::cos(alpha) / std::sin(alpha);
  v = p_face * std::cos(alpha + delta) - x[2] * d * w;
  p = s.penetration_direction != 0 ? penetration_kn(s, x[0], x[1], x[2], x[3], x[4]) : 0.0;
}

}  // namespace

namespace {

// Solves A x = b (5 x 5) by Gauss-Jordan with partial pivoting, giving the
// inverse too; false when a pivot is below 1e-10 of the largest diagonal
// (a direction the data do not see).
bool solve5(const double (&a_in)[5][5], const double (&b_in)[5], double (&x)[5], double (&inv)[5][5]) {
  double a[5][5], b[5];
  double scale = 0.0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      a[i][j] = a_in[i][j];
      inv[i][j] = i == j ? 1.0 : 0.0;
    }
    b[i] = b_in[i];
    scale = std::max(scale, std::fabs(a_in[i][i]));
  }
  if (!(scale > 0.0)) return false;
  for (int col = 0; col < 5; ++col) {
    int piv = col;
    for (int r = col + 1; r < 5; ++r)
      if (std::fabs(a[r][col]) > std::fabs(a[piv][col])) piv = r;
    if (!(std::fabs(a[piv][col]) > 1e-10 * scale)) return false;
    for (int k = 0; k < 5; ++k) {
      std::swap(a[col][k], a[piv][k]);
      std::swap(inv[col][k], inv[piv][k]);
    }
    std::swap(b[col], b[piv]);
    const double d = a[col][col];
    for (int k = 0; k < 5; ++k) {
      a[col][k] /= d;
      inv[col][k] /= d;
    }
    b[col] /= d;
    for (int r = 0; r < 5; ++r)
      if (r != col) {
        const double m = a[r][col];
        for (int k = 0; k < 5; ++k) {
          a[r][k] -= m * a[col][k];
          inv[r][k] -= m * inv[col][k];
        }
        b[r] -= m * b[col];
      }
  }
  for (int i = 0; i < 5; ++i) x[i] = b[i];
  return true;
}

}  // namespace

SoilEstimator::Refined SoilEstimator::refine(const std::array<double, kSoilFieldCount>& start,
                                             bool refresh_angles) const {
  Refined out;
  out.x = start;
  if (memory_size_ == 0) return out;
  const double lambda = settings_.forgetting_per_sample;
  double max_rake = 0.0;
  for (std::size_t k = 0; k < memory_size_; ++k) max_rake = std::max(max_rake, memory_[k].sample.rake_deg);
  // Physical values: weight > 0, cohesion and adhesion >= 0, 0 <= delta <=
  // phi, and a failure wedge at every rake remembered.
  auto clip = [&](std::array<double, 5>& x) {
    x[0] = std::max(x[0], 0.01 * settings_.prior.unit_weight_n_per_m3 * kToKilo);
    x[1] = std::max(x[1], 0.0);
    x[2] = std::max(x[2], 0.0);
    x[3] = std::clamp(x[3], 0.0, std::min(88.0, 178.0 - max_rake));
    x[4] = std::clamp(x[4], 0.0, std::min(x[3], 178.0 - max_rake - x[3]));
  };
  // The weighted cost, and with want_normal the normal equations, at x.
  auto evaluate = [&](const std::array<double, 5>& x, bool want_normal, double (&f)[5][5],
                      double (&g)[5], double& weight) {
    double cost = 0.0;
    weight = 0.0;
    if (want_normal)
      for (int i = 0; i < 5; ++i) {
        g[i] = 0.0;
        for (int j = 0; j < 5; ++j) f[i][j] = 0.0;
      }
    constexpr double kAngleStep = 0.01;  // degrees, for the angles' derivatives
    for (std::size_t k = 0; k < memory_size_; ++k) {
      const Remembered& r = memory_[k];
      const double w = std::pow(lambda, double(r.age));
      double h0, v0, p0;
      model_hv(r.sample, r.beta_rad, x, h0, v0, p0);
      const bool pen = r.sample.penetration_direction != 0;
      const double rh = r.sample.horizontal_n * kToKilo - h0, rv = r.sample.vertical_n * kToKilo - v0;
      const double rp = pen ? r.sample.penetration_n * kToKilo - p0 : 0.0;
      cost += w * (rh * rh + rv * rv + rp * rp);
      weight += (pen ? 3.0 : 2.0) * w;
      if (!want_normal) continue;
      double jh[5], jv[5], jp[5];
      for (int i = 0; i < 5; ++i) {
        std::array<double, 5> xi = x;
        const double dx = i < 3 ? 1.0 : kAngleStep;  // linear: any step is exact
        xi[std::size_t(i)] += dx;
        double h, v, p;
        model_hv(r.sample, r.beta_rad, xi, h, v, p);
        jh[i] = (h - h0) / dx;
        jv[i] = (v - v0) / dx;
        jp[i] = pen ? (p - p0) / dx : 0.0;
      }
      for (int i = 0; i < 5; ++i) {
        g[i] += w * (jh[i] * rh + jv[i] * rv + jp[i] * rp);
        for (int j = 0; j < 5; ++j) f[i][j] += w * (jh[i] * jh[j] + jv[i] * jv[j] + jp[i] * jp[j]);
      }
    }
    return cost;
  };
  double f[5][5], g[5], weight = 0.0;
  std::array<double, 5> x = start;
  clip(x);
  // Each remembered cut's failure angle at the starting point (the force is
  // stationary in it, so the steps below may keep it fixed); from the
  // previous estimate they are still those it found.
  for (std::size_t k = 0; refresh_angles && k < memory_size_; ++k) {
    Remembered& r = memory_[k];
    EarthmovingParams p;
    p.rake_angle_deg = r.sample.rake_deg;
    p.soil.unit_weight_n_per_m3 = x[0] / kToKilo;
    p.soil.cohesion_pa = x[1] / kToKilo;
    p.soil.adhesion_pa = x[2] / kToKilo;
    p.soil.internal_friction_deg = x[3];
    p.soil.soil_tool_friction_deg = x[4];
    r.beta_rad = beta_star(p, r.sample, p.soil.unit_weight_n_per_m3 * r.sample.pile_m, r.beta_rad);
  }
  double cost = evaluate(x, true, f, g, weight);
  double mu = 1e-3;
  constexpr int kIterations = 2;  // from a warm start; the next sample goes on
  for (int it = 0; it < kIterations; ++it) {
    double a[5][5], step[5], inv[5][5];
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) a[i][j] = f[i][j] + (i == j ? mu * f[i][i] + 1e-12 : 0.0);
    if (!solve5(a, g, step, inv)) break;
    std::array<double, 5> trial = x;
    for (int i = 0; i < 5; ++i) trial[std::size_t(i)] += step[i];
    clip(trial);
    double f2[5][5], g2[5], w2;
    const double trial_cost = evaluate(trial, true, f2, g2, w2);
    if (trial_cost < cost) {
      x = trial;
      cost = trial_cost;
      std::copy(&f2[0][0], &f2[0][0] + 25, &f[0][0]);
      std::copy(g2, g2 + 5, g);
      mu = std::max(mu / 3.0, 1e-7);
    } else {
      mu *= 10.0;
    }
  }
  out.x = x;
  out.cost = cost;
  out.weight = weight;
  out.ok = true;
  // The residual variance with the sensor's floor, and Cov = sigma^2 F^-1.
  const double noise_kn = settings_.force_noise_n * kToKilo;
  const double sigma2 = std::max(cost / std::max(weight - 5.0, 1.0), noise_kn * noise_kn);
  constexpr double kUnbounded = 1e12;  // (parameter units)^2: nothing known
  out.var.fill(kUnbounded);
  double zero[5] = {}, unused[5], inv[5][5];
  if (solve5(f, zero, unused, inv))
    for (int i = 0; i < 5; ++i) {
      const double v = sigma2 * inv[i][i];
      if (v >= 0.0 && std::isfinite(v)) out.var[std::size_t(i)] = std::min(v, kUnbounded);
    }
  return out;
}

}  // namespace terracut
