// Contacts: payload-vehicle distances and contact episodes.

#include "hpa/sim/contacts.h"

#include <Eigen/Core>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>


namespace hpa::sim {

namespace {

// Signed distance (m) from point p to an axis-aligned box of half sizes h at the origin
// (negative inside: minus the depth to the nearest face).
double BoxSignedDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// Signed distance (m) from point p to a solid cylinder of radius r and half height h along z at
// the origin (negative inside).
double CylinderSignedDistance(const Eigen::Vector3d& p, double r, double h) {
  const Eigen::Vector2d q(p.head<2>().norm() - r, std::abs(p.z()) - h);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

}  // namespace

Contacts::Contacts(const ContactsBinding& binding) : b_(binding) {
  if (b_.model == nullptr || b_.data == nullptr) {
    throw std::logic_error("sim::Contacts: a binding without its world's model and data");
  }
}

void Contacts::Reset() {
  counts_ = ContactCounts{};
  for (bool& t : touching_) t = false;
  payload_quad_min_distance_m_ = PayloadQuadDistance();
}

double Contacts::PayloadQuadDistance() const {
  const Eigen::Vector3d p_WL_W(b_.data->xpos + 3 * b_.payload_body);
  const double radius_m = b_.model->geom_size[3 * b_.payload_geom];
  // the payload centre in a geom's frame: R_WG^T (p_WL - p_WG)
  auto in_geom = [&](int g) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_WG(b_.data->geom_xmat +
                                                                              9 * g);
    return Eigen::Vector3d(R_WG.transpose() *
                           (p_WL_W - Eigen::Vector3d(b_.data->geom_xpos + 3 * g)));
  };
  const int box = b_.quad_box_geom;
  double d = BoxSignedDistance(in_geom(box), Eigen::Vector3d(b_.model->geom_size + 3 * box));
  for (int i = 0; i < 4; ++i) {
    const int g = b_.rotor_disc_geom[i];
    d = std::min(d, CylinderSignedDistance(in_geom(g), b_.model->geom_size[3 * g],
                                           b_.model->geom_size[3 * g + 1]));
  }
  return d - radius_m;
}

bool Contacts::Update() {
  bool now[5] = {false, false, false, false, false};  // the ContactCounts fields, in order
  bool rotor_strike = false;
  for (int i = 0; i < b_.data->ncon; ++i) {
    const mjContact& c = b_.data->contact[i];
    for (const auto& [a, b] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}}) {
      if (a == b_.payload_geom) {
        if (b == b_.quad_box_geom) now[0] = true;
        for (int r = 0; r < 4; ++r) rotor_strike |= b == b_.rotor_disc_geom[r];
        if (b == b_.ground_geom) now[2] = true;
        if (b == b_.gripper_geom) now[4] = true;
      }
      if (a == b_.ground_geom && b_.model->geom_bodyid[b] == b_.quad_body) now[3] = true;
    }
  }
  now[1] = rotor_strike;
  int* counts[5] = {&counts_.payload_body, &counts_.payload_rotor, &counts_.payload_ground,
                    &counts_.quad_ground, &counts_.payload_gripper};
  for (int k = 0; k < 5; ++k) {
    if (now[k] && !touching_[k]) ++*counts[k];
    touching_[k] = now[k];
  }
  payload_quad_min_distance_m_ = std::min(payload_quad_min_distance_m_, PayloadQuadDistance());
  return rotor_strike;
}

}  // namespace hpa::sim
