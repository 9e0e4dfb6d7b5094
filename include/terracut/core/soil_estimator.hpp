// Online estimation of a soil's material from the physical force on a blade
// cutting it: what a teleoperation remote learns of its soil and sends to
// the operator's local model (session/mmt.hpp, docs/teleoperation.md).
//
// The model is the cutting force itself (earthmoving.hpp): McKyes' form of
// the Fundamental Earthmoving Equation with side crescents and the pile's
// surcharge q = gamma h_pile,
//   P = w [gamma (d^2 N_gamma + h_pile d N_q) + c d N_c + c_a d N_a]
//   H = P sin(alpha + delta) + c_a d w cot(alpha)
//   V = P cos(alpha + delta) - c_a d w,
// whose factors N depend on the friction angles phi, delta, the rake alpha,
// d / w and the failure-plane angle beta (the one that minimises P), and,
// while the edge moves down or up in the soil, the penetration force
// (penetration.hpp: Terzaghi's bearing under the tip, the faces' friction),
// whose factors depend on phi and delta. At fixed angles (phi, delta, beta)
// all of them are linear in the unit weight gamma, the cohesion c and the
// adhesion c_a (Luengo, Singh & Cannon 1998, "Modeling and identification
// of soil-tool interaction in automated excavation", IROS; Tan, Zweiri,
// Althoefer & Seneviratne 2005, "Online soil parameter estimation scheme
// based on Newton-Raphson method for autonomous excavation", IEEE/ASME
// Trans. Mechatronics 10). So:
//   - a grid of candidate friction-angle pairs (phi, delta), delta <= phi;
//   - for each, recursive least squares with exponential forgetting of
//     (gamma, c, c_a) over the samples' equations (H, V and the penetration
//     force when there is one), the factors taken at the beta* that the
//     candidate's current fit gives (as the force model finds it), and the
//     forgetting-weighted sum of its squared residuals;
//   - the estimate: the admissible pair of least cost refined by
//     Levenberg-Marquardt on all five parameters over the cuts remembered
//     (a ring of the newest samples), its standard uncertainties from the
//     information matrix there (the residual variance times F^-1, F the
//     forgetting-weighted J^T J), and a parameter identifiable when its
//     uncertainty is at most its resolution (SoilEstimatorSettings);
//   - a change of soil: a run of samples the estimate mispredicts that no
//     one material fits with the remembered ones restarts the memory
//     (covariance resetting).
// The residual variance has a floor: a force sensor's noise, so that a
// simulated remote whose force is the model itself does not report zero
// uncertainty.
//
// It takes the physical force only (soil_sample: the cutting and surcharge
// parts of ToolForce, the force of the soil on the tool as a sensor would
// read it): never a rendered force, nor one under a haptic device's
// low-speed cap, which holds two different soils at the same force.
//
// Cost: one failure-angle search per candidate and sample, which advance()
// spreads over ticks so that a 1 kHz loop pays a bounded slice per tick;
// the refinement (about a millisecond over 256 remembered cuts) runs every
// fifth sample, on the tick that finishes it. Allocates only at
// construction.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/earthmoving.hpp"
#include "terracut/core/enum_names.hpp"
#include "terracut/core/material.hpp"
#include "terracut/core/tool_force.hpp"

namespace terracut {

/// The fields of SoilMaterial that the estimator fits, in this order.
enum class SoilField : int {
  kUnitWeight = 0,        ///< unit_weight_n_per_m3
  kCohesion = 1,          ///< cohesion_pa
  kAdhesion = 2,          ///< adhesion_pa
  kInternalFriction = 3,  ///< internal_friction_deg
  kSoilToolFriction = 4,  ///< soil_tool_friction_deg
};
inline constexpr int kSoilFieldCount = 5;
/// The fields' names in SoilMaterial (and a scenario's soil: section):
/// to_string(SoilField) (core/enum_names.hpp).
inline constexpr EnumName<SoilField> kSoilFieldNames[] = {
    {SoilField::kUnitWeight, "unit_weight_n_per_m3"},
    {SoilField::kCohesion, "cohesion_pa"},
    {SoilField::kAdhesion, "adhesion_pa"},
    {SoilField::kInternalFriction, "internal_friction_deg"},
    {SoilField::kSoilToolFriction, "soil_tool_friction_deg"}};
constexpr std::span<const EnumName<SoilField>> enum_names(SoilField) { return kSoilFieldNames; }
/// The field's value in a material.
double field_value(const SoilMaterial& m, SoilField field);

/// One observation: the cut and the physical force of the soil on the blade
/// (the earthmoving equation's part: cutting and surcharge).
struct SoilSample {
  double width_m = 0.0;     ///< engaged width across the motion, m, > 0
  double depth_m = 0.0;     ///< depth of undisturbed soil ahead, m, > 0
  double pile_m = 0.0;      ///< soil piled over the failure wedge, m, >= 0
  double rake_deg = 90.0;   ///< the blade's rake angle, degrees, (0, 180)
  double horizontal_n = 0.0;  ///< the force resisting the horizontal motion, N
  double vertical_n = 0.0;    ///< the vertical force, N, positive pushing the blade down (McKyes' sign)
  /// The penetration force's part (penetration.hpp), when the edge moves
  /// vertically while embedded: -1 down (the bearing under the tip and the
  /// faces' friction), +1 up (the faces only), 0 none (the rest unused).
  int penetration_direction = 0;
  double penetration_n = 0.0;      ///< its magnitude, N, >= 0
  double embedment_depth_m = 0.0;  ///< the edge's depth below the soil beside it, m, > 0
  double embedded_length_m = 0.0;  ///< the length of edge that deep, m, > 0
  double edge_thickness_m = 0.0;   ///< the cutting edge's thickness, m, > 0
};

/// The sample of a step: the physical force's cutting and surcharge parts
/// (ToolForce::cutting_n + surcharge_n) resolved along the motion and the
/// vertical, with the cut they came from, and its penetration part while
/// the edge also moves vertically in the soil (edge_thickness_m: the
/// blade's). valid is false (nothing to learn) while the tool does not move
/// horizontally faster than kRestSpeed_m_per_s or cuts nothing (no engaged
/// width or depth). Nothing a device renders enters: ToolForce is the
/// physical force (tool_force.hpp).
struct StepSample {
  bool valid = false;
  SoilSample sample{};
};
StepSample soil_sample(const ToolForce& force, const ToolMotion& motion, double rake_deg,
                       double edge_thickness_m) noexcept;

/// Settings of the estimator; validated at construction.
struct SoilEstimatorSettings {
  /// Forgetting factor per sample, (0, 1]: a memory of about 1 / (1 - lambda)
  /// samples. 1: no forgetting.
  double forgetting_per_sample = 0.97;
  /// The candidate internal friction angles, degrees: from phi_min_deg to
  /// phi_max_deg in steps of angle_step_deg (and delta from 0 to phi in the
  /// same steps). phi_min_deg in [0, 89), phi_max_deg in (phi_min, 89),
  /// angle_step_deg in [0.5, 20].
  double phi_min_deg = 2.0;
  double phi_max_deg = 44.0;
  double angle_step_deg = 2.0;
  /// Where the linear parameters start (and the repose angle, which the
  /// force does not depend on, is taken from): the local model's soil.
  SoilMaterial prior{};
  /// The prior's standard deviations of (gamma, c, c_a), in N/m^3, Pa, Pa,
  /// each > 0: how far the estimate may move on the first samples.
  std::array<double, 3> prior_sd{1e5, 1e5, 1e5};
  /// A force sensor's noise, N, > 0: the floor of the residuals' standard
  /// deviation (a simulated remote whose force is the model itself would
  /// otherwise report no uncertainty at all).
  double force_noise_n = 2.0;
  /// A parameter is identifiable when its standard uncertainty is at most
  /// its resolution: (gamma N/m^3, c Pa, c_a Pa, phi deg, delta deg), each > 0.
  std::array<double, kSoilFieldCount> resolution{1000.0, 300.0, 300.0, 2.0, 2.0};
};

/// Empty when valid, else a message naming the field.
std::string validate(const SoilEstimatorSettings& settings);

/// What the estimator knows of the soil.
struct SoilEstimate {
  /// The best-fitting material (repose from the prior; negative linear
  /// values clipped to 0 here, their fit kept in the uncertainty).
  SoilMaterial material{};
  /// Standard uncertainty of each fitted field (SoilField order), in its
  /// unit (N/m^3, Pa, Pa, deg, deg).
  std::array<double, kSoilFieldCount> sd{};
  /// Bit (1 << field) set when the field is identifiable: its uncertainty at
  /// most its resolution.
  std::uint32_t identifiable = 0;
  std::int64_t samples = 0;        ///< samples taken in so far
  double residual_rms_n = 0.0;     ///< RMS of the best candidate's residuals (forgetting-weighted), N
  bool known = false;              ///< at least one sample taken in
  /// Times the memory restarted on a change of soil (a run of samples far
  /// off the estimate; soil_estimator.cpp).
  std::int64_t restarts = 0;

  bool is_identifiable(SoilField f) const { return (identifiable >> int(f)) & 1u; }
};

class SoilEstimator {
 public:
  /// Throws InputError naming the field when the settings are invalid.
  explicit SoilEstimator(const SoilEstimatorSettings& settings);

  /// Takes a sample in at once (every candidate): begin() + advance(all).
  /// Returns false when it was left out (a sample that is not finite, or
  /// outside the ranges in SoilSample).
  bool add(const SoilSample& sample);
  /// Starts a sample to be taken in over several advance() calls; false when
  /// one is already under way or the sample is left out.
  bool begin(const SoilSample& sample);
  /// Takes the current sample into up to `candidates` more candidates;
  /// returns true when that finished it (the estimate then moves).
  bool advance(int candidates);
  bool busy() const { return pending_; }
  int candidate_count() const { return int(candidates_.size()); }

  /// The newest estimate (recomputed when a sample finishes).
  const SoilEstimate& estimate() const { return estimate_; }
  /// Forgets every sample.
  void reset();
  const SoilEstimatorSettings& settings() const { return settings_; }

 private:
  struct Candidate {
    double phi_deg = 0.0, delta_deg = 0.0;
    std::array<double, 3> theta{};      // gamma kN/m^3, c kPa, c_a kPa
    std::array<double, 9> p{};          // covariance of theta, row-major
    double cost = 0.0;                  // forgetting-weighted sum of squared residuals, kN^2
    double weight = 0.0;                // forgetting-weighted number of equations
    double beta_rad = 0.0;              // beta* of the previous sample (0: none yet)
  };
  struct Remembered {
    SoilSample sample{};
    double beta_rad = 0.0;  // the failure angle the estimate found for it
    std::int64_t age = 0;   // samples since
  };
  void restart_memory();
  struct Refined {
    std::array<double, kSoilFieldCount> x{};    // gamma kN/m^3, c kPa, c_a kPa, phi deg, delta deg
    std::array<double, kSoilFieldCount> var{};  // their variances
    double cost = 0.0, weight = 0.0;            // over the cuts in memory, kN^2
    bool ok = false;
  };
  Refined refine(const std::array<double, kSoilFieldCount>& start, bool refresh_angles) const;
  double newest_residual_rms_n(const std::array<double, kSoilFieldCount>& x, std::int64_t newest) const;
  void take(Candidate& c, const SoilSample& s) const;
  double failure_angle(Candidate& c, const EarthmovingParams& params, const SoilSample& s,
                       double q) const;
  void finish_sample();
  int index(int phi_i, int delta_i) const;  // -1 when not a candidate

  SoilEstimatorSettings settings_;
  std::vector<Candidate> candidates_;
  int phi_steps_ = 0;  // candidates per row: delta_i in [0, phi_i]
  std::vector<int> row_start_;
  SoilSample sample_{};
  bool pending_ = false;
  std::size_t next_ = 0;
  // A ring of the newest cuts; their failure angles are refreshed by refine().
  mutable std::vector<Remembered> memory_;
  std::size_t memory_next_ = 0, memory_size_ = 0;
  std::int64_t since_reset_ = 0;  // samples since the memory last restarted
  int surprises_ = 0;             // consecutive samples far off the estimate
  std::array<double, kSoilFieldCount> previous_x_{};  // the previous refined fit
  bool refined_before_ = false;
  double calm_rms_n_ = 0.0;       // the residuals' RMS before the misses began, N
  SoilEstimate estimate_{};
};

}  // namespace terracut
