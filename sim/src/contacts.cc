// Contacts: payload-vehicle distances and contact episodes.

#include "hpa/sim/contacts.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "hpa/sim/world.h"

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

void Contacts::Reset() {
  counts_ = ContactCounts{};
  for (bool& t : touching_) t = false;
  payload_quad_min_distance_m_ = PayloadQuadDistance();
}

double Contacts::PayloadQuadDistance() const {
  const Eigen::Vector3d p_WL_W(w_.data_->xpos + 3 * w_.ids_.payload_body);
  const double radius_m = w_.model_->geom_size[3 * w_.ids_.payload_geom];
  // the payload centre in a geom's frame: R_WG^T (p_WL - p_WG)
  auto in_geom = [&](int g) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_WG(w_.data_->geom_xmat +
                                                                              9 * g);
    return Eigen::Vector3d(R_WG.transpose() *
                           (p_WL_W - Eigen::Vector3d(w_.data_->geom_xpos + 3 * g)));
  };
  const int box = w_.ids_.quad_box_geom;
  double d = BoxSignedDistance(in_geom(box), Eigen::Vector3d(w_.model_->geom_size + 3 * box));
  for (int i = 0; i < 4; ++i) {
    const int g = w_.ids_.rotor_disc_geom[i];
    d = std::min(d, CylinderSignedDistance(in_geom(g), w_.model_->geom_size[3 * g],
                                           w_.model_->geom_size[3 * g + 1]));
  }
  return d - radius_m;
}

void Contacts::Update() {
  bool now[5] = {false, false, false, false, false};  // the ContactCounts fields, in order
  bool rotor_strike = false;
  for (int i = 0; i < w_.data_->ncon; ++i) {
    const mjContact& c = w_.data_->contact[i];
    for (const auto& [a, b] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}}) {
      if (a == w_.ids_.payload_geom) {
        if (b == w_.ids_.quad_box_geom) now[0] = true;
        for (int r = 0; r < 4; ++r) rotor_strike |= b == w_.ids_.rotor_disc_geom[r];
        if (b == w_.ids_.ground_geom) now[2] = true;
        if (b == w_.ids_.gripper_geom) now[4] = true;
      }
      if (a == w_.ids_.ground_geom && w_.model_->geom_bodyid[b] == w_.ids_.quad_body) now[3] = true;
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
  if (rotor_strike) w_.LatchCrash("rotor_strike");
}

}  // namespace hpa::sim
