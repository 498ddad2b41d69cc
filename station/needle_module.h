#pragma once
// The needle–vessel module: the needle, held at its tail by the tool, against the tube (a
// torus segment). Each step it computes the clearance by the SP method (thesis chapter 4,
// common/geometry/arc_torus_sp.h) and, on contact, a penalty force pushing the tool back
// into the tube (the "impact force when the tool hits a narrow tube" of thesis §2.1).
// Every kErrorCheckPeriod steps it also evaluates the clearance by dense sampling of the arc
// and publishes |SP − sampled| as its error estimate.

#include "common/geometry/arc_torus.h"
#include "common/geometry/arc_torus_sp.h"
#include "station/module.h"

namespace microdex::station {

class NeedleModule final : public Module {
 public:
  static constexpr int kErrorCheckPeriod = 100;  // steps
  static constexpr int kErrorCheckSamples = 257;

  explicit NeedleModule(const scene::SceneModel& scene);
  const char* name() const override { return "needle"; }
  void Step(const ToolInput& in, Eigen::Vector3d& f_T_W) override;
  void WriteSnapshot(TickSnapshot& snapshot) const override;
  double error_estimate() const override { return error_estimate_m_; }
  const char* error_kind() const override { return "sp_vs_sampled_m"; }
  std::uint32_t warnings() const override { return warnings_; }
  bool fault() const override {
    return clearance_.status == geometry::ClearanceStatus::kOk && clearance_.contact;
  }
  double fault_value() const override { return clearance_.clearance_m; }

  const geometry::ArcTorusClearance& clearance() const { return clearance_; }

 private:
  Eigen::Isometry3d X_TN_;
  double wall_stiffness_N_per_m_;
  geometry::ArcDef arc_;
  geometry::TorusSegmentDef torus_;
  geometry::ArcTorusClearance clearance_;
  double error_estimate_m_;
  std::uint32_t warnings_ = 0;
};

// Clearance by sampling the arc at n points (brute force, the error reference): the minimum
// of r − distance to the core circle over the samples inside the azimuth range; NaN when
// none is.
double CalcSampledClearance(const geometry::ArcDef& arc, const geometry::TorusSegmentDef& torus,
                            int n);

}  // namespace microdex::station
