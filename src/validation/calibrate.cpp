// Calibration of a soil material from records. See calibrate.hpp.
#include "terracut/validation/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut::validation {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

constexpr double kUndetermined = std::numeric_limits<double>::infinity();

// The standard uncertainty of the mean: the sample standard deviation over
// sqrt(n); undetermined (+inf) for one value.
double mean_uncertainty(const std::vector<double>& v) {
  if (v.size() < 2) return kUndetermined;
  const double m = mean(v);
  double q = 0.0;
  for (double x : v) q += (x - m) * (x - m);
  return std::sqrt(q / double(v.size() - 1)) / std::sqrt(double(v.size()));
}

std::vector<double> numbers_at(const Json& j, const char* key, const fs::path& file) {
  std::vector<double> out;
  if (!j.contains(key)) return out;
  if (!j[key].is_array()) throw InputError(file.string() + ": " + key + ": expected a list of numbers");
  for (const Json& v : j[key]) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw InputError(file.string() + ": " + key + ": expected a list of finite numbers");
    out.push_back(v.get<double>());
  }
  return out;
}

MaterialTests::Stress stress_at(const Json& v, const char* sigma, const char* tau, const fs::path& file,
                                const std::string& where) {
  if (!v.is_object() || !v.contains(sigma) || !v.contains(tau) || !v[sigma].is_number() || !v[tau].is_number())
    throw InputError(file.string() + ": " + where + ": expected {\"" + sigma + "\": .., \"" + tau + "\": ..}");
  MaterialTests::Stress s{v[sigma].get<double>(), v[tau].get<double>()};
  if (!(std::isfinite(s.sigma_pa) && s.sigma_pa > 0.0 && std::isfinite(s.tau_pa) && s.tau_pa >= 0.0))
    throw InputError(file.string() + ": " + where + ": the normal stress must be > 0 and the shear stress >= 0");
  return s;
}

// A SoilMaterial field by name.
double* field_of(SoilMaterial& m, const std::string& name) {
  if (name == "unit_weight_n_per_m3") return &m.unit_weight_n_per_m3;
  if (name == "internal_friction_deg") return &m.internal_friction_deg;
  if (name == "cohesion_pa") return &m.cohesion_pa;
  if (name == "soil_tool_friction_deg") return &m.soil_tool_friction_deg;
  if (name == "adhesion_pa") return &m.adhesion_pa;
  if (name == "repose_deg") return &m.repose_deg;
  return nullptr;
}

// Solves the n x n system a x = b (n small), Gaussian elimination with
// partial pivoting; false when singular.
bool solve(std::vector<double> a, std::vector<double> b, int n, std::vector<double>& x) {
  for (int c = 0; c < n; ++c) {
    int p = c;
    for (int r = c + 1; r < n; ++r)
      if (std::abs(a[std::size_t(r * n + c)]) > std::abs(a[std::size_t(p * n + c)])) p = r;
    if (!(std::abs(a[std::size_t(p * n + c)]) > 1e-300)) return false;
    for (int k = 0; k < n; ++k) std::swap(a[std::size_t(c * n + k)], a[std::size_t(p * n + k)]);
    std::swap(b[std::size_t(c)], b[std::size_t(p)]);
    for (int r = c + 1; r < n; ++r) {
      const double f = a[std::size_t(r * n + c)] / a[std::size_t(c * n + c)];
      for (int k = c; k < n; ++k) a[std::size_t(r * n + k)] -= f * a[std::size_t(c * n + k)];
      b[std::size_t(r)] -= f * b[std::size_t(c)];
    }
  }
  x.assign(std::size_t(n), 0.0);
  for (int r = n - 1; r >= 0; --r) {
    double s = b[std::size_t(r)];
    for (int k = r + 1; k < n; ++k) s -= a[std::size_t(r * n + k)] * x[std::size_t(k)];
    x[std::size_t(r)] = s / a[std::size_t(r * n + r)];
  }
  return true;
}

// A field the force does not depend on has a zero column in the Jacobian
// (a zero row and column in a = J'J): its equation becomes dx_i = 0 so that
// the others are still solved. Returns which fields were pinned.
std::vector<bool> pin_unidentified(std::vector<double>& a, std::vector<double>& b, int n) {
  double largest = 0.0;
  for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(a[std::size_t(i * n + i)]));
  std::vector<bool> pinned(std::size_t(n), false);
  for (int i = 0; i < n; ++i) {
    if (std::abs(a[std::size_t(i * n + i)]) > 1e-12 * largest && largest > 0.0) continue;
    pinned[std::size_t(i)] = true;
    for (int j = 0; j < n; ++j) a[std::size_t(i * n + j)] = a[std::size_t(j * n + i)] = 0.0;
    a[std::size_t(i * n + i)] = 1.0;
    b[std::size_t(i)] = 0.0;
  }
  return pinned;
}

}  // namespace

MaterialTests read_material_tests(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot be read");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::exception& e) {
    throw InputError(file.string() + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) throw InputError(file.string() + ": expected an object");
  MaterialTests t;
  if (j.contains("shear_tests")) {
    // A DEM's results/material.json (validation/dem/README.md).
    t.bulk_density_kg_per_m3 = numbers_at(j, "bulk_density_kg_per_m3_per_seed", file);
    t.repose_deg = numbers_at(j, "repose_deg_per_seed", file);
    for (const auto& [seed, tests] : j["shear_tests"].items())
      for (const Json& v : tests)
        t.shear.push_back(stress_at(v, "sigma_normal_pa", "tau_peak_pa", file, "shear_tests." + seed));
    if (j.contains("soil_tool_tests"))
      for (const auto& [seed, tests] : j["soil_tool_tests"].items())
        for (const Json& v : tests) {
          if (!v.contains("tan_delta") || !v["tan_delta"].is_number())
            throw InputError(file.string() + ": soil_tool_tests." + seed + ": tan_delta missing");
          const MaterialTests::Stress s = stress_at(v, "sigma_normal_pa", "sigma_normal_pa", file,
                                                    "soil_tool_tests." + seed);
          t.plate.push_back({s.sigma_pa, s.sigma_pa * v["tan_delta"].get<double>()});
        }
    return t;
  }
  for (const auto& [key, value] : j.items())
    if (key != "bulk_density_kg_per_m3" && key != "repose_deg" && key != "shear" && key != "plate")
      throw InputError(file.string() + ": " + key +
                       ": unknown test (bulk_density_kg_per_m3, repose_deg, shear, plate)");
  t.bulk_density_kg_per_m3 = numbers_at(j, "bulk_density_kg_per_m3", file);
  t.repose_deg = numbers_at(j, "repose_deg", file);
  for (const char* key : {"shear", "plate"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_array()) throw InputError(file.string() + ": " + key + ": expected a list");
    int i = 0;
    for (const Json& v : j[key])
      (std::string(key) == "shear" ? t.shear : t.plate)
          .push_back(stress_at(v, "sigma_pa", "tau_pa", file, std::string(key) + "[" + std::to_string(i++) + "]"));
  }
  return t;
}

Calibration calibrate_from_tests(const MaterialTests& t, const SoilMaterial& start) {
  Calibration c;
  c.material = start;
  if (!t.bulk_density_kg_per_m3.empty()) {
    const double rho = mean(t.bulk_density_kg_per_m3), u = mean_uncertainty(t.bulk_density_kg_per_m3);
    c.material.unit_weight_n_per_m3 = rho * kStandardGravity_m_per_s2;
    c.fields.push_back({"unit_weight_n_per_m3", c.material.unit_weight_n_per_m3, u * kStandardGravity_m_per_s2,
                        "the bulk density's mean over " + std::to_string(t.bulk_density_kg_per_m3.size()) +
                            " tests x 9.81"});
  }
  for (const auto& [name, values] : {std::pair{"bulk_density_kg_per_m3", &t.bulk_density_kg_per_m3},
                                      std::pair{"repose_deg", &t.repose_deg}})
    if (values->size() == 1) c.notes.push_back(std::string(name) + ": one test; its uncertainty needs a second");
  if (t.plate.size() == 1) c.notes.push_back("plate: one test; its uncertainty needs a second");
  if (!t.repose_deg.empty()) {
    c.material.repose_deg = mean(t.repose_deg);
    c.fields.push_back({"repose_deg", c.material.repose_deg, mean_uncertainty(t.repose_deg),
                        "the mean over " + std::to_string(t.repose_deg.size()) + " tests"});
  }
  if (!t.shear.empty()) {
    // The Mohr-Coulomb line tau = c + sigma tan(phi), least squares, with the
    // standard errors of its slope and intercept.
    const std::size_t n = t.shear.size();
    double sx = 0, sy = 0;
    for (const auto& s : t.shear) {
      sx += s.sigma_pa;
      sy += s.tau_pa;
    }
    const double mx = sx / double(n), my = sy / double(n);
    double sxx = 0, sxy = 0;
    for (const auto& s : t.shear) {
      sxx += (s.sigma_pa - mx) * (s.sigma_pa - mx);
      sxy += (s.sigma_pa - mx) * (s.tau_pa - my);
    }
    if (n < 2 || !(sxx > 0.0))
      throw InputError("shear: the Mohr-Coulomb line needs tests at two normal stresses at least");
    const double slope = sxy / sxx, intercept = my - slope * mx;
    double rss = 0;
    for (const auto& s : t.shear) rss += std::pow(s.tau_pa - intercept - slope * s.sigma_pa, 2);
    // Two points fix the line exactly: no degree of freedom is left to
    // estimate its scatter, so its uncertainty is undetermined.
    const double var = n > 2 ? rss / double(n - 2) : kUndetermined;
    const double se_slope = std::sqrt(var / sxx), se_int = std::sqrt(var * (1.0 / double(n) + mx * mx / sxx));
    if (n == 2) c.notes.push_back("shear: two tests fix the line exactly; its uncertainty needs a third");
    c.material.internal_friction_deg = std::atan(slope) / kDeg;
    c.material.cohesion_pa = std::max(0.0, intercept);
    c.fields.push_back({"internal_friction_deg", c.material.internal_friction_deg,
                        se_slope / (1.0 + slope * slope) / kDeg,
                        "the slope of the Mohr-Coulomb line through " + std::to_string(n) + " shear tests"});
    c.fields.push_back({"cohesion_pa", c.material.cohesion_pa, se_int, "its intercept"});
    if (intercept < 0.0)
      c.notes.push_back("the shear tests' line crosses below zero stress (" + format_number(intercept) +
                        " Pa): cohesion set to 0");
    c.rms_residual = std::sqrt(rss / double(n));
    c.rms_relative = my > 0.0 ? c.rms_residual / my : 0.0;
  }
  if (!t.plate.empty()) {
    // tan(delta): the line through the origin tau = sigma tan(delta).
    double sxx = 0, sxy = 0;
    for (const auto& s : t.plate) {
      sxx += s.sigma_pa * s.sigma_pa;
      sxy += s.sigma_pa * s.tau_pa;
    }
    const double k = sxy / sxx;
    double rss = 0;
    for (const auto& s : t.plate) rss += std::pow(s.tau_pa - k * s.sigma_pa, 2);
    const double var = t.plate.size() > 1 ? rss / double(t.plate.size() - 1) : kUndetermined;
    c.material.soil_tool_friction_deg = std::atan(k) / kDeg;
    c.fields.push_back({"soil_tool_friction_deg", c.material.soil_tool_friction_deg,
                        std::sqrt(var / sxx) / (1.0 + k * k) / kDeg,
                        "the friction of " + std::to_string(t.plate.size()) + " plate tests (a line through zero)"});
  }
  std::string kept;
  for (const char* field : {"unit_weight_n_per_m3", "internal_friction_deg", "cohesion_pa", "soil_tool_friction_deg",
                            "adhesion_pa", "repose_deg"})
    if (std::none_of(c.fields.begin(), c.fields.end(), [&](const FittedField& f) { return f.name == field; }))
      kept += std::string(kept.empty() ? "" : ", ") + field;
  if (!kept.empty()) c.notes.push_back("no test gives " + kept + ": kept at the start material's values");
  if (std::string e = validate(c.material); !e.empty()) throw InputError("the tests give " + e);
  return c;
}

ForceRecord read_force_record(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv.string() + ": cannot be read");
  std::string line;
  std::getline(in, line);
  if (line.rfind("t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n", 0) != 0)
    throw InputError(csv.string() + ":1: expected the header t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n");
  ForceRecord r;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    double v[11];
    std::stringstream s(line);
    std::string cell;
    for (double& x : v) {
      if (!std::getline(s, cell, ','))
        throw InputError(csv.string() + ":" + std::to_string(row) + ": 11 numbers expected");
      try {
        std::size_t used = 0;
        x = std::stod(cell, &used);
        if (used != cell.size() || !std::isfinite(x)) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw InputError(csv.string() + ":" + std::to_string(row) + ": '" + cell + "' is not a finite number");
      }
    }
    if (!r.t_s.empty() && !(v[0] > r.t_s.back()))
      throw InputError(csv.string() + ":" + std::to_string(row) + ": times must increase");
    if (r.t_s.size() >= 2) {
      const double dt0 = r.t_s[1] - r.t_s[0], dt = v[0] - r.t_s.back();
      if (std::abs(dt - dt0) > 1e-3 * dt0)
        throw InputError(csv.string() + ":" + std::to_string(row) + ": the samples are not at a fixed rate (" +
                         format_number(dt) + " s after the previous one, the first two are " +
                         format_number(dt0) + " s apart)");
    }
    r.t_s.push_back(v[0]);
    const Quat q{v[4], v[5], v[6], v[7]};
    if (!(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z > 1e-12))
      throw InputError(csv.string() + ":" + std::to_string(row) + ": the orientation qw,qx,qy,qz is zero");
    r.pose.push_back({{v[1], v[2], v[3]}, normalized(q)});
    r.force_n.push_back({v[8], v[9], v[10]});
  }
  if (r.t_s.size() < 2) throw InputError(csv.string() + ": fewer than two samples");
  return r;
}

namespace {

// The record's windows: the means of the horizontal force along the motion
// (the resistance, > 0) and of the vertical force, over window_n samples,
// from the first sample at or after from_t_s; the motion's direction from
// terracut's heading at each step.
std::vector<double> window_means(const ForceRecord& rec, const std::vector<Vec3>& force,
                                 const std::vector<Vec3>& heading, std::size_t first, std::size_t window_n) {
  std::vector<double> out;
  for (std::size_t s = first; s + window_n <= force.size(); s += window_n) {
    double h = 0.0, v = 0.0;
    for (std::size_t k = s; k < s + window_n; ++k) {
      h += -(force[k].x * heading[k].x + force[k].z * heading[k].z);
      v += force[k].y;
    }
    out.push_back(h / double(window_n));
    out.push_back(v / double(window_n));
  }
  (void)rec;
  return out;
}

}  // namespace

Calibration calibrate_from_force_record(const SimParams& params, const std::vector<float>& heights,
                                        const ForceRecord& record, const RecordFit& fit) {
  const int n = int(fit.fields.size());
  if (n < 1) throw InputError("calibrate: no field to fit");
  if (fit.max_iterations < 1) throw InputError("calibrate: max_iterations must be at least 1");
  if (!(fit.window_s > 0.0) || !std::isfinite(fit.window_s)) throw InputError("calibrate: window_s must be > 0");
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < i; ++k)
      if (fit.fields[std::size_t(i)] == fit.fields[std::size_t(k)])
        throw InputError("calibrate: " + fit.fields[std::size_t(i)] + " is given twice");
  if (record.t_s.size() < 2 || record.pose.size() != record.t_s.size() || record.force_n.size() != record.t_s.size())
    throw InputError("calibrate: the record needs two samples or more, each with a pose and a force");
  for (std::size_t k = 1; k < record.t_s.size(); ++k) {
    const double dt0 = record.t_s[1] - record.t_s[0], dt = record.t_s[k] - record.t_s[k - 1];
    if (!(dt0 > 0.0) || std::abs(dt - dt0) > 1e-3 * dt0)
      throw InputError("calibrate: the record's samples are not at a fixed rate (sample " + std::to_string(k) + ")");
  }
  for (const std::string& f : fit.fields) {
    SoilMaterial probe;
    if (!field_of(probe, f))
      throw InputError("calibrate: " + f + ": not a field of the soil material (unit_weight_n_per_m3, "
                       "internal_friction_deg, cohesion_pa, soil_tool_friction_deg, adhesion_pa, repose_deg)");
  }
  // The record's rate must be the simulation's: one step per sample.
  const double dt = (record.t_s.back() - record.t_s.front()) / double(record.t_s.size() - 1);
  if (std::abs(dt * params.rate_hz - 1.0) > 1e-3)
    throw InputError("calibrate: the record's samples are " + format_number(dt) + " s apart, the run steps at " +
                     format_number(params.rate_hz) + " Hz: resample the record or give its rate");
  const std::size_t window_n = std::max<std::size_t>(1, std::size_t(std::lround(fit.window_s * params.rate_hz)));
  std::size_t first = 0;
  while (first < record.t_s.size() && record.t_s[first] < fit.from_t_s) ++first;

  // One run of the path with a material: the windows' means.
  Calibration out;
  std::vector<double> measured;
  const auto run = [&](const SoilMaterial& m) {
    SimParams p = params;
    p.soil.material = m;
    Simulation sim(p, heights);
    std::vector<Vec3> force, heading;
    force.reserve(record.pose.size());
    heading.reserve(record.pose.size());
    for (const BladePose& pose : record.pose) {
      const StepOutput& o = sim.step(pose);
      force.push_back(o.force.total_n);
      heading.push_back(o.motion.heading);
    }
    ++out.evaluations;
    if (measured.empty()) measured = window_means(record, record.force_n, heading, first, window_n);
    return window_means(record, force, heading, first, window_n);
  };

  // The fields' bounds (their ranges) and finite-difference steps.
  SoilMaterial m = params.soil.material;
  const std::size_t nn = static_cast<std::size_t>(n);
  std::vector<double> x(nn), lo(nn), hi(nn), h(nn);
  for (int i = 0; i < n; ++i) {
    const std::string& f = fit.fields[std::size_t(i)];
    x[std::size_t(i)] = *field_of(m, f);
    const Range& r = find_range(material_ranges(), f);
    lo[std::size_t(i)] = r.lo + (r.ends == RangeEnds::kOpenLow || r.ends == RangeEnds::kOpen ? 1e-6 : 0.0);
    hi[std::size_t(i)] = std::min(r.hi, f.ends_with("_deg") ? 85.0 : 1e7);
    h[std::size_t(i)] = f.ends_with("_deg") ? 0.05 : std::max(1.0, 1e-3 * std::abs(x[std::size_t(i)]));
  }
  const auto material_at = [&](const std::vector<double>& v) {
    SoilMaterial t = m;
    for (int i = 0; i < n; ++i) *field_of(t, fit.fields[std::size_t(i)]) = v[std::size_t(i)];
    return t;
  };
  // The residuals at v; nullopt where the material is not a valid one (a
  // trial step past a joint limit such as rake + delta + phi < 179).
  const auto try_residuals = [&](const std::vector<double>& v) -> std::optional<std::vector<double>> {
    const SoilMaterial t = material_at(v);
    if (!validate(t).empty()) return std::nullopt;
    SimParams trial = params;
    trial.soil.material = t;
    if (!validate(trial).empty()) return std::nullopt;
    std::vector<double> model = run(t);
    for (std::size_t k = 0; k < model.size(); ++k) model[k] -= measured[k];
    return model;
  };
  const auto residuals = [&](const std::vector<double>& v) {
    auto r = try_residuals(v);
    if (!r) throw InputError("calibrate: the start material is not valid for this scenario");
    return *r;
  };
  // The Jacobian at x by forward differences, backward at an upper bound
  // or where the forward step leaves the valid materials; a column neither
  // can take stays zero (the field is then pinned).
  const auto jacobian_at = [&](const std::vector<double>& x0, const std::vector<double>& r0) {
    std::vector<double> jac(r0.size() * std::size_t(n), 0.0);
    for (int i = 0; i < n; ++i) {
      for (double sign : {1.0, -1.0}) {
        std::vector<double> xp = x0;
        double step = sign * h[std::size_t(i)];
        if (sign > 0.0 && xp[std::size_t(i)] + step > hi[std::size_t(i)]) continue;
        if (sign < 0.0 && xp[std::size_t(i)] + step < lo[std::size_t(i)]) continue;
        xp[std::size_t(i)] += step;
        const auto rp = try_residuals(xp);
        if (!rp) continue;
        for (std::size_t k = 0; k < r0.size(); ++k) jac[k * std::size_t(n) + std::size_t(i)] = ((*rp)[k] - r0[k]) / step;
        break;
      }
    }
    return jac;
  };
  const auto rss_of = [](const std::vector<double>& r) {
    double s = 0.0;
    for (double e : r) s += e * e;
    return s;
  };
  std::vector<double> r = residuals(x);
  if (r.size() < std::size_t(n))
    throw InputError("calibrate: the record has " + std::to_string(r.size()) + " window values for " +
                     std::to_string(n) + " fields: too short");
  double rss = rss_of(r), lambda = 1e-3;
  std::vector<double> jac;  // m x n, row-major
  for (int iter = 0; iter < fit.max_iterations; ++iter) {
    jac = jacobian_at(x, r);
    // Levenberg-Marquardt: (J'J + lambda diag(J'J)) dx = -J'r.
    bool improved = false;
    for (int tries = 0; tries < 8 && !improved; ++tries) {
      std::vector<double> a(std::size_t(n * n), 0.0), b(std::size_t(n), 0.0), dx;
      for (std::size_t k = 0; k < r.size(); ++k)
        for (int i = 0; i < n; ++i) {
          b[std::size_t(i)] -= jac[k * std::size_t(n) + std::size_t(i)] * r[k];
          for (int j = 0; j < n; ++j)
            a[std::size_t(i * n + j)] += jac[k * std::size_t(n) + std::size_t(i)] * jac[k * std::size_t(n) + std::size_t(j)];
        }
      for (int i = 0; i < n; ++i) a[std::size_t(i * n + i)] *= 1.0 + lambda;
      pin_unidentified(a, b, n);
      if (!solve(a, b, n, dx)) {
        lambda *= 10.0;
        continue;
      }
      std::vector<double> xn = x;
      for (int i = 0; i < n; ++i)
        xn[std::size_t(i)] = std::clamp(x[std::size_t(i)] + dx[std::size_t(i)], lo[std::size_t(i)], hi[std::size_t(i)]);
      const auto trial = try_residuals(xn);
      if (!trial) {  // outside the valid materials: a shorter step
        lambda *= 10.0;
        continue;
      }
      const std::vector<double>& rn = *trial;
      const double rssn = rss_of(rn);
      if (rssn < rss) {
        const double gain = (rss - rssn) / std::max(rss, 1e-300);
        x = xn;
        r = rn;
        rss = rssn;
        lambda = std::max(1e-7, lambda / 10.0);
        improved = true;
        if (gain < 1e-6) iter = fit.max_iterations;  // converged
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }

  // The uncertainty: the covariance s^2 (J'J)^-1 at the solution (the
  // Jacobian taken again there); undetermined without a degree of freedom.
  jac = jacobian_at(x, r);
  const std::size_t mrows = r.size();
  const double s2 = mrows > std::size_t(n) ? rss / double(mrows - std::size_t(n)) : kUndetermined;
  if (mrows <= std::size_t(n))
    out.notes.push_back("the record has as many window values as fields: the fit is exact and its uncertainty "
                        "undetermined (a longer record, or longer --window-s fewer fields)");
  std::vector<double> a(std::size_t(n * n), 0.0);
  for (std::size_t k = 0; k < mrows; ++k)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        a[std::size_t(i * n + j)] += jac[k * std::size_t(n) + std::size_t(i)] * jac[k * std::size_t(n) + std::size_t(j)];
  out.material = material_at(x);
  std::vector<double> unused(std::size_t(n), 0.0);
  const std::vector<bool> pinned = pin_unidentified(a, unused, n);
  for (int i = 0; i < n; ++i) {
    std::vector<double> e(std::size_t(n), 0.0), col;
    e[std::size_t(i)] = 1.0;
    double var = std::numeric_limits<double>::infinity();
    if (!pinned[std::size_t(i)] && solve(a, e, n, col) && col[std::size_t(i)] > 0.0) var = s2 * col[std::size_t(i)];
    const bool bound = x[std::size_t(i)] <= lo[std::size_t(i)] || x[std::size_t(i)] >= hi[std::size_t(i)];
    out.fields.push_back({fit.fields[std::size_t(i)], x[std::size_t(i)], std::sqrt(var),
                          pinned[std::size_t(i)] ? std::string("not identified: kept at its start")
                                                 : std::string("fitted to the record's force") +
                                                       (bound ? " (at a bound of its range)" : "")});
    if (pinned[std::size_t(i)])
      out.notes.push_back(fit.fields[std::size_t(i)] + ": the record's force does not change with it (on this "
                                                       "path and soil model): not identifiable, kept at its start");
  }
  double ms = 0.0;
  for (double v : measured) ms += v * v;
  out.rms_residual = std::sqrt(rss / double(mrows));
  out.rms_relative = ms > 0.0 ? out.rms_residual / std::sqrt(ms / double(mrows)) : 0.0;
  return out;
}

std::string material_yaml(const SoilMaterial& m) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "soil:\n  model: flow                     # the repose is the flow's\n  unit_weight_n_per_m3: %.6g   # density %.6g kg/m^3\n  internal_friction_deg: %.6g\n"
                "  cohesion_pa: %.6g\n  soil_tool_friction_deg: %.6g\n  adhesion_pa: %.6g\n  repose_deg: %.6g\n",
                m.unit_weight_n_per_m3, m.density_kg_per_m3(), m.internal_friction_deg, m.cohesion_pa,
                m.soil_tool_friction_deg, m.adhesion_pa, m.repose_deg);
  return buf;
}

}  // namespace terracut::validation
