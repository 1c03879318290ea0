#include "hpa/models/state.h"

namespace hpa {

const char* ToString(CableMode mode) { return mode == CableMode::kTaut ? "taut" : "slack"; }

StateVector SystemState::ToVector() const {
  StateVector x;
  x << p_WL_W, v_WL_W, p_WQ_W, v_WQ_W, q_WB.w(), q_WB.x(), q_WB.y(), q_WB.z(), w_B;
  return x;
}

void SystemState::FromVector(const StateVector& x) {
  using I = StateIndex;
  p_WL_W = x.segment<3>(I::kPayloadPos);
  v_WL_W = x.segment<3>(I::kPayloadVel);
  p_WQ_W = x.segment<3>(I::kQuadPos);
  v_WQ_W = x.segment<3>(I::kQuadVel);
  q_WB = Eigen::Quaterniond(x(I::kQuat), x(I::kQuat + 1), x(I::kQuat + 2), x(I::kQuat + 3));
  q_WB.normalize();
  w_B = x.segment<3>(I::kBodyRate);
}

bool SystemState::AllFinite() const { return std::isfinite(time_s) && ToVector().allFinite(); }

}  // namespace hpa
