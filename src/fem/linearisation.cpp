// SPDX-License-Identifier: Apache-2.0
#include "fem/linearisation.hpp"

#include <algorithm>

#include "fem/rotation.hpp"

namespace mica {

namespace {

// For each element e in order, body(e, F1) with F1 its deformation gradient at x_end, after
// R_end[e] = proper_rotation(F1) when `rotate`. The elements are taken four at a time, for
// proper_rotations4 (a pair and a single at the end).
template <class Body>
void for_each_end_gradient(const FemModel& m, const Vec3List& x_end, bool rotate, std::vector<Mat3>& R_end,
                           Body&& body) {
  const size_t n = m.elements.size();
  const auto F = [&](size_t e) { return deformation_gradient(m.elements[e], x_end); };
  size_t first = 0;
  for (; first + 4 <= n; first += 4) {
    const Mat3 F1[4] = {F(first), F(first + 1), F(first + 2), F(first + 3)};  // made in place (a copy would stall)
    if (rotate) proper_rotations4(F1, &R_end[first]);
    for (size_t j = 0; j < 4; ++j) body(first + j, F1[j]);
  }
  Mat3 tail[3];
  for (size_t j = 0; first + j < n; ++j) tail[j] = F(first + j);
  if (rotate) proper_rotations(tail, R_end.data() + first, int(n - first));
  for (size_t j = 0; first + j < n; ++j) body(first + j, tail[j]);
}

}  // namespace

ScreenEnergies screen_energies(const FemModel& m, const Vec3List& x, const Vec3List& x_end, const std::vector<Mat3>& R,
                               std::vector<Mat3>& R_end, bool with_start) {
  ScreenEnergies out;
  for_each_end_gradient(m, x_end, true, R_end, [&](size_t e, const Mat3& F1) {
    const TetElement& el = m.elements[e];
    const std::array<double, 2> u = elastic_energies(el, m.lame[e], R_end[e], R[e], F1);
    out.u_end += u[0];
    out.u_lin_end += u[1];
    if (with_start) out.u_lin_start += elastic_energy(el, m.lame[e], R[e], deformation_gradient(el, x));
  });
  return out;
}

LinearisationEnergies linearisation_energies(const FemModel& m, const Vec3List& x, const Vec3List& x_end,
                                             const Vec3List& v, const std::vector<Mat3>* R_lin,
                                             std::vector<Mat3>& R_end, const std::vector<Mat3>* R_start,
                                             bool with_start_stiffness, const std::vector<TwistModes>& modes,
                                             const Vec3List& v_lin) {
  LinearisationEnergies out;
  const Mat3 I = Mat3::Identity();
  const bool corot = R_lin != nullptr;
  const bool twist = !modes.empty();
  for_each_end_gradient(m, x_end, corot, R_end, [&](size_t e, const Mat3& F1) {
    const TetElement& el = m.elements[e];
    const Mat3& R = corot ? (*R_lin)[e] : I;
    const std::array<double, 2> u = elastic_energies(el, m.lame[e], corot ? R_end[e] : I, R, F1);
    out.u_end += u[0];
    out.u_lin_end += u[1];
    out.u_lin_start += elastic_energy(el, m.lame[e], R, deformation_gradient(el, x));
    // v^T (R Ke R^T) v is twice the strain energy of the displacement v in the frame R.
    const Mat3 Fv = deformation_gradient(el, v);
    out.vKv += 2 * elastic_energy(el, m.lame[e], R, Fv + R);
    if (with_start_stiffness) {
      const Mat3& Rs = corot ? (*R_start)[e] : I;
      out.vKv_start += 2 * elastic_energy(el, m.lame[e], Rs, Fv + Rs);
    }
    if (!twist) return;
    const TwistModes& t = modes[e];
    for (int32_t q = 0; q < t.count; ++q) {
      double cv = 0, cl = 0;
      for (int a = 0; a < 4; ++a) {
        cv += t.q[q][a].dot(v[el.nodes[a]]);
        cl += t.q[q][a].dot(v_lin[el.nodes[a]]);
      }
      out.gvv += t.weight[q] * cv * cv;
      out.gdd += t.weight[q] * (cv - cl) * (cv - cl);
      out.gll += t.weight[q] * cl * cl;
    }
  });
  return out;
}

void add_twist_stiffness(const FemModel& m, const Vec3List& x_lin, const Vec3List& v_lin, double h,
                         std::vector<TwistModes>& modes, BlockValues& A, Vec3List& f_int) {
  modes.resize(m.elements.size());
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const TetElement& el = m.elements[e];
    TwistModes& t = modes[e];
    t = twist_modes(el, m.lame[e], deformation_gradient(el, x_lin));
    for (int32_t q = 0; q < t.count; ++q) {
      double c = 0;
      for (int a = 0; a < 4; ++a) c += t.q[q][a].dot(v_lin[el.nodes[a]]);
      const double w = t.weight[q];
      for (int a = 0; a < 4; ++a) {
        f_int[el.nodes[a]] += (h * w * c) * t.q[q][a];
        for (int c2 = 0; c2 < 4; ++c2) A[m.slots[e][4 * a + c2]] += (h * h * w) * t.q[q][a] * t.q[q][c2].transpose();
      }
    }
  }
}

}  // namespace mica
