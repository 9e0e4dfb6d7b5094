// The online soil estimator (core/soil_estimator.hpp): a soil of known
// material cut at varied depths, widths and rakes is identified within its
// reported uncertainty; what the cuts cannot tell apart is reported as not
// identifiable; only the physical force enters.
#include "terracut/core/soil_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "terracut/core/error.hpp"
#include "terracut/core/penetration.hpp"

namespace terracut {
namespace {

// A sample of the equation itself for `soil`: the force a remote whose soil
// is `soil` measures (the physical force is this equation; tool_force.hpp).
SoilSample sample_of(const SoilMaterial& soil, double width_m, double depth_m, double pile_m,
                     double rake_deg) {
  EarthmovingParams p;
  p.soil = soil;
  p.rake_angle_deg = rake_deg;
  const EarthmovingResult r =
      earthmoving_force(p, width_m, depth_m, soil.unit_weight_n_per_m3 * pile_m);
  SoilSample s;
  s.width_m = width_m;
  s.depth_m = depth_m;
  s.pile_m = pile_m;
  s.rake_deg = rake_deg;
  s.horizontal_n = r.horizontal_n;
  s.vertical_n = r.vertical_n;
  return s;
}

// Cuts of a blade whose depth, width and rake vary as a study's scenarios
// make them: depths 1-12 cm, widths 0.2-0.6 m, rakes 60-90 degrees, a pile
// of up to 5 cm (seeded).
void feed_varied(SoilEstimator& est, const SoilMaterial& soil, int samples, unsigned seed,
                 double noise_n = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> depth(0.01, 0.12), width(0.2, 0.6), rake(60.0, 90.0),
      pile(0.0, 0.05);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < samples; ++i) {
    SoilSample s = sample_of(soil, width(rng), depth(rng), pile(rng), rake(rng));
    s.horizontal_n += noise_n * noise(rng);
    s.vertical_n += noise_n * noise(rng);
    ASSERT_TRUE(est.add(s));
  }
}

SoilEstimatorSettings sand_prior() {
  SoilEstimatorSettings s;
  s.prior = soil_preset(SoilPreset::kDrySand);
  s.forgetting_per_sample = 0.995;  // 200 samples of memory
  return s;
}

// Every identifiable field lies within 2 of its standard uncertainties of
// the truth (about 95 % for a normal error); the force it predicts at a cut
// it has seen is within 2 %.
void expect_identified(const SoilEstimate& e, const SoilMaterial& truth, const char* name) {
  int identified = 0;
  for (int f = 0; f < kSoilFieldCount; ++f) {
    const SoilField field = SoilField(f);
    if (!e.is_identifiable(field)) continue;
    ++identified;
    const double want = field_value(truth, field), got = field_value(e.material, field);
    EXPECT_LE(std::fabs(got - want), 2.0 * e.sd[std::size_t(f)] + 1e-9)
        << name << " " << to_string(field) << ": estimate " << got << " +- "
        << e.sd[std::size_t(f)] << ", truth " << want;
  }
  EXPECT_GE(identified, 2) << name;
  // Its predictions are as good as its fit: within three of its residuals'
  // RMS and 1 %.
  for (double depth : {0.03, 0.08}) {
    EarthmovingParams pt, pe;
    pt.soil = truth;
    pe.soil = e.material;
    const double ht = earthmoving_force(pt, 0.4, depth).horizontal_n;
    const double he = earthmoving_force(pe, 0.4, depth).horizontal_n;
    EXPECT_NEAR(he, ht, 3.0 * e.residual_rms_n + 0.01 * ht) << name << " at depth " << depth;
  }
}

TEST(SoilEstimator, IdentifiesKnownMaterialsWithinTheirUncertainty) {
  for (SoilPreset preset : {SoilPreset::kClay, SoilPreset::kGravel, SoilPreset::kLooseSand}) {
    SoilEstimator est(sand_prior());
    const SoilMaterial truth = soil_preset(preset);
    feed_varied(est, truth, 250, 7);
    const SoilEstimate& e = est.estimate();
    EXPECT_TRUE(e.known);
    EXPECT_EQ(e.samples, 250);
    expect_identified(e, truth, std::string(to_string(preset)).c_str());
  }
}

// With a force sensor's noise of 5 N the estimate stays within its (now
// larger) uncertainty.
TEST(SoilEstimator, NoisyForcesStayWithinTheReportedUncertainty) {
  SoilEstimatorSettings s = sand_prior();
  s.force_noise_n = 5.0;
  SoilEstimator est(s);
  const SoilMaterial truth = soil_preset(SoilPreset::kClay);
  feed_varied(est, truth, 300, 11, 5.0);
  expect_identified(est.estimate(), truth, "clay with noise");
}

// One depth, one width, one rake: the weight's d^2 and the cohesion's d
// cannot be told apart, so neither is claimed identifiable, yet the fitted
// material predicts that cut's force.
TEST(SoilEstimator, OneCutDoesNotIdentifyWeightAndCohesionApart) {
  SoilEstimator est(sand_prior());
  const SoilMaterial truth = soil_preset(SoilPreset::kClay);
  const SoilSample s = sample_of(truth, 0.4, 0.08, 0.0, 90.0);
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(est.add(s));
  const SoilEstimate& e = est.estimate();
  EXPECT_FALSE(e.is_identifiable(SoilField::kUnitWeight)) << "sd gamma " << e.sd[0];
  EXPECT_FALSE(e.is_identifiable(SoilField::kCohesion)) << "sd c " << e.sd[1];
  EarthmovingParams pe;
  pe.soil = e.material;
  EXPECT_NEAR(earthmoving_force(pe, 0.4, 0.08).horizontal_n, s.horizontal_n,
              0.02 * s.horizontal_n);
}

// The same single cut, with the edge also moving down and up in the soil:
// the bearing under the tip grows with phi as e^(pi tan phi) while the
// cutting force does not tell phi from the weight and the cohesion, so
// the penetration force pins the internal friction (and with it the rest).
TEST(SoilEstimator, PenetrationTellsTheFrictionAngle) {
  SoilEstimator est(sand_prior());
  const SoilMaterial truth = soil_preset(SoilPreset::kClay);
  for (int i = 0; i < 300; ++i) {
    SoilSample s = sample_of(truth, 0.4, 0.08, 0.0, 90.0);
    s.penetration_direction = i % 2 == 0 ? -1 : 1;
    s.edge_thickness_m = 0.02;
    s.embedded_length_m = 0.4;
    s.embedment_depth_m = 0.02 + 0.0003 * (i % 200);
    const PenetrationResult r = penetration_resistance(truth, 0.02, 0.4, s.embedment_depth_m);
    s.penetration_n = s.penetration_direction < 0 ? r.down_n() : r.up_n();
    ASSERT_TRUE(est.add(s));
  }
  const SoilEstimate& e = est.estimate();
  EXPECT_TRUE(e.is_identifiable(SoilField::kInternalFriction)) << "sd phi " << e.sd[3];
  expect_identified(e, truth, "clay, one cut with penetration");
}

// A change of soil is followed within the forgetting's memory: after 3
// memories of gravel the estimate predicts the gravel's force.
TEST(SoilEstimator, FollowsAChangeOfSoil) {
  SoilEstimatorSettings s = sand_prior();
  s.forgetting_per_sample = 0.97;  // about 33 samples
  SoilEstimator est(s);
  feed_varied(est, soil_preset(SoilPreset::kClay), 200, 3);
  const SoilMaterial gravel = soil_preset(SoilPreset::kGravel);
  feed_varied(est, gravel, 100, 4);
  EXPECT_GE(est.estimate().restarts, 1);  // the change was seen as one
  // The fit's own residual (the grid's angles against the truth's) is the
  // tolerance of its predictions: three of them, and 1 %.
  EarthmovingParams pt, pe;
  pt.soil = gravel;
  pe.soil = est.estimate().material;
  const double tolerance_n = 3.0 * est.estimate().residual_rms_n;
  for (double depth : {0.03, 0.08}) {
    const double ht = earthmoving_force(pt, 0.4, depth).horizontal_n;
    EXPECT_NEAR(earthmoving_force(pe, 0.4, depth).horizontal_n, ht, tolerance_n + 0.01 * ht)
        << depth;
  }
}

// Spreading a sample over ticks gives the same estimate as taking it at once.
TEST(SoilEstimator, SlicedSamplesGiveTheSameEstimate) {
  SoilEstimator whole(sand_prior()), sliced(sand_prior());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> depth(0.02, 0.1);
  const SoilMaterial truth = soil_preset(SoilPreset::kGravel);
  for (int i = 0; i < 50; ++i) {
    const SoilSample s = sample_of(truth, 0.4, depth(rng), 0.0, 90.0);
    ASSERT_TRUE(whole.add(s));
    ASSERT_TRUE(sliced.begin(s));
    EXPECT_FALSE(sliced.begin(s));  // one at a time
    int calls = 0;
    while (!sliced.advance(7)) ++calls;
    EXPECT_EQ(calls, (sliced.candidate_count() + 6) / 7 - 1);
  }
  for (int f = 0; f < kSoilFieldCount; ++f)
    EXPECT_EQ(field_value(whole.estimate().material, SoilField(f)),
              field_value(sliced.estimate().material, SoilField(f)));
}

// Only the physical force enters: a step's sample is the cutting and
// surcharge parts along the motion, none at rest, whatever else acts.
TEST(SoilEstimator, StepSampleIsThePhysicalCuttingForceOnly) {
  ToolForce f;
  f.engaged_width_m = 0.4;
  f.cut_depth_m = 0.05;
  f.pile_m = 0.01;
  f.cutting_n = {0.0, 80.0, 300.0};  // moving along -Z: resisted along +Z, lifted
  f.surcharge_n = {0.0, 10.0, 50.0};
  f.penetration_n = {0.0, 999.0, 0.0};  // not the cutting force
  f.bodies_n = {0.0, 0.0, 5000.0};      // a rock: not the soil
  ToolMotion m;
  m.velocity_m_per_s = {0.0, -0.2, -1.0};
  const StepSample s = soil_sample(f, m, 90.0, 0.02);
  ASSERT_TRUE(s.valid);
  EXPECT_DOUBLE_EQ(s.sample.horizontal_n, 350.0);
  EXPECT_DOUBLE_EQ(s.sample.vertical_n, -90.0);
  EXPECT_DOUBLE_EQ(s.sample.depth_m, 0.05);
  EXPECT_EQ(s.sample.penetration_direction, 0);  // not embedded: no penetration part
  // Embedded and moving down: the penetration part (the physical one) too.
  f.embedment_depth_m = 0.05;
  f.embedded_length_m = 0.4;
  const StepSample pen = soil_sample(f, m, 90.0, 0.02);
  ASSERT_TRUE(pen.valid);
  EXPECT_EQ(pen.sample.penetration_direction, -1);
  EXPECT_DOUBLE_EQ(pen.sample.penetration_n, 999.0);
  EXPECT_DOUBLE_EQ(pen.sample.horizontal_n, 350.0);  // still without the rock
  m.velocity_m_per_s = {0.0, -0.2, 0.0};  // no horizontal motion: nothing mobilised
  EXPECT_FALSE(soil_sample(f, m, 90.0, 0.02).valid);
  m.velocity_m_per_s = {0.0, 0.0, -1.0};
  f.cut_depth_m = 0.0;  // no cut
  EXPECT_FALSE(soil_sample(f, m, 90.0, 0.02).valid);
}

TEST(SoilEstimator, RefusesBadSettingsAndSamples) {
  SoilEstimatorSettings s;
  s.forgetting_per_sample = 1.5;
  try {
    SoilEstimator est(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("forgetting_per_sample"), std::string::npos) << e.what();
  }
  s = {};
  s.angle_step_deg = 0.0;
  EXPECT_THROW(SoilEstimator{s}, InputError);
  s = {};
  s.prior.unit_weight_n_per_m3 = -1.0;
  try {
    SoilEstimator est(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("prior.unit_weight_n_per_m3"), std::string::npos)
        << e.what();
  }
  SoilEstimator est{SoilEstimatorSettings{}};
  SoilSample bad = sample_of(soil_preset(SoilPreset::kClay), 0.4, 0.05, 0.0, 90.0);
  bad.horizontal_n = std::nan("");
  EXPECT_FALSE(est.add(bad));
  bad = sample_of(soil_preset(SoilPreset::kClay), 0.4, 0.05, 0.0, 90.0);
  bad.depth_m = 0.0;
  EXPECT_FALSE(est.add(bad));
  EXPECT_EQ(est.estimate().samples, 0);
  EXPECT_FALSE(est.estimate().known);
  EXPECT_EQ(est.estimate().restarts, 0);
}

}  // namespace
}  // namespace terracut
