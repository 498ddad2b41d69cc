#include "station/page_device.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace microdex::station {
namespace {

void ReadValues(std::istringstream& in, double* v, int n, const std::string& what) {
  for (int i = 0; i < n; ++i) {
    if (!(in >> v[i]) || !std::isfinite(v[i])) {
      throw std::invalid_argument(what + ": expected " + std::to_string(n) + " finite numbers");
    }
  }
  std::string extra;
  if (in >> extra) throw std::invalid_argument(what + ": unexpected '" + extra.substr(0, 32) + "'");
}

}  // namespace

PageInput ParsePageInput(const std::string& message) {
  std::istringstream in(message);
  std::string verb;
  in >> verb;
  PageInput p;
  if (verb == "move") {
    p.kind = PageInput::Kind::kMove;
    ReadValues(in, p.v.data(), 3, "move");
    if (Eigen::Vector3d(p.v[0], p.v[1], p.v[2]).norm() > kMaxPageMove_m) {
      throw std::invalid_argument("move: longer than 2 mm in one message");
    }
  } else if (verb == "turn") {
    p.kind = PageInput::Kind::kTurn;
    ReadValues(in, p.v.data(), 3, "turn");
    if (Eigen::Vector3d(p.v[0], p.v[1], p.v[2]).norm() > kMaxPageTurn_rad) {
      throw std::invalid_argument("turn: more than 0.2 rad in one message");
    }
  } else if (verb == "grip") {
    p.kind = PageInput::Kind::kGrip;
    ReadValues(in, p.v.data(), 1, "grip");
    if (!(p.v[0] >= 0 && p.v[0] <= 1)) throw std::invalid_argument("grip: expected 0..1");
  } else if (verb == "buttons") {
    p.kind = PageInput::Kind::kButtons;
    ReadValues(in, p.v.data(), 1, "buttons");
    if (!(p.v[0] >= 0 && p.v[0] <= 65535) || p.v[0] != std::floor(p.v[0])) {
      throw std::invalid_argument("buttons: expected an integer 0..65535");
    }
    p.buttons = static_cast<std::uint32_t>(p.v[0]);
  } else {
    throw std::invalid_argument("unknown device message '" + verb.substr(0, 32) +
                                "' (expected move, turn, grip or buttons)");
  }
  return p;
}

PageDevice::PageDevice(const Eigen::Isometry3d& X_WT_start)
    : ring_(kRingCapacity), p_W_start_(X_WT_start.translation()) {
  sample_.X_WT = X_WT_start;
}

DeviceSample PageDevice::Read(std::uint64_t /*step*/) {
  PageInput in;
  while (ring_.TryPop(in)) {
    const Eigen::Vector3d v(in.v[0], in.v[1], in.v[2]);
    switch (in.kind) {
      case PageInput::Kind::kMove: {
        const Eigen::Vector3d lo = p_W_start_.array() - kWorkspaceHalf_m;
        const Eigen::Vector3d hi = p_W_start_.array() + kWorkspaceHalf_m;
        sample_.X_WT.translation() = (sample_.X_WT.translation() + v).cwiseMax(lo).cwiseMin(hi);
        break;
      }
      case PageInput::Kind::kTurn: {
        const double angle = v.norm();
        if (angle > 0) {
          const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
          const Eigen::Quaterniond q(R * sample_.X_WT.linear());
          sample_.X_WT.linear() = q.normalized().toRotationMatrix();
        }
        break;
      }
      case PageInput::Kind::kGrip:
        sample_.gripper = in.v[0];
        break;
      case PageInput::Kind::kButtons:
        sample_.buttons = in.buttons;
        break;
    }
  }
  return sample_;
}

}  // namespace microdex::station
