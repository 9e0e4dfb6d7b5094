// Python arguments read into terracut's types (bindings.hpp).
#include <cmath>
#include <string>

#include "bindings.hpp"

namespace terracut::python {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// A C-contiguous float64 copy (or view) of any array-like; InputError naming
// `what` when it holds something that is not a number.
py::array_t<double, py::array::c_style | py::array::forcecast> doubles(py::handle obj,
                                                                         const std::string& what) {
  // ensure() gives a null array (the Python error cleared) when obj cannot
  // be read as numbers.
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) throw InputError(what + ": expected numbers");
  return a;
}

Vec3 vec3(py::handle obj, const std::string& what) {
  const auto a = fixed<3>(obj, what);
  return {a[0], a[1], a[2]};
}

py::tuple tuple3(const Vec3& v) { return py::make_tuple(v.x, v.y, v.z); }
py::tuple tuple4(const Quat& q) { return py::make_tuple(q.w, q.x, q.y, q.z); }
py::tuple rect_tuple(const Rect& r) { return py::make_tuple(r.c0, r.r0, r.c1, r.r1); }

// A pose as 7 numbers x, y, z, qw, qx, qy, qz: finite, the quaternion not zero.
BladePose pose_from(const double* p, const std::string& what) {
  for (int i = 0; i < 7; ++i)
    if (!std::isfinite(p[i])) throw InputError(what + ": must be finite");
  const double norm2 = p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6];
  if (!(norm2 > 1e-24)) throw InputError(what + ": the quaternion (qw, qx, qy, qz) must not be zero");
  return {{p[0], p[1], p[2]}, Quat{p[3], p[4], p[5], p[6]}};
}

// Fast path for a single pose given as a tuple or list of 7 numbers (the
// common case of step(pose) in a loop): no numpy array is made.
bool pose_from_sequence(py::handle obj, BladePose* pose) {
  if (!(PyTuple_Check(obj.ptr()) || PyList_Check(obj.ptr()))) return false;
  if (PySequence_Fast_GET_SIZE(obj.ptr()) != 7) return false;
  PyObject** items = PySequence_Fast_ITEMS(obj.ptr());
  double p[7];
  for (int i = 0; i < 7; ++i) {
    if (!PyFloat_Check(items[i]) && !PyLong_Check(items[i])) return false;
    p[i] = PyFloat_AsDouble(items[i]);
    if (p[i] == -1.0 && PyErr_Occurred()) throw py::error_already_set();
  }
  *pose = pose_from(p, "pose");
  return true;
}

}  // namespace terracut::python
