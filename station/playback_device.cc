#include "station/playback_device.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "common/base/input_error.h"

namespace microdex::station {
namespace {

constexpr const char* kColumns[] = {"p_x", "p_y", "p_z",     "q_w",    "q_x",
                                    "q_y", "q_z", "gripper", "buttons"};
constexpr int kColumnCount = 9;

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

}  // namespace

PlaybackDevice::PlaybackDevice(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path, 0, "", "cannot open file");
  std::string line;
  int line_no = 0;
  if (!std::getline(f, line)) throw InputError(path, 1, "", "empty file (expected a header)");
  ++line_no;
  {
    std::stringstream ss(line);
    std::string cell;
    int i = 0;
    while (std::getline(ss, cell, ',')) {
      if (i >= kColumnCount || Trim(cell) != kColumns[i]) {
        throw InputError(path, 1, "header", "expected p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons");
      }
      ++i;
    }
    if (i != kColumnCount) {
      throw InputError(path, 1, "header", "expected p_x,p_y,p_z,q_w,q_x,q_y,q_z,gripper,buttons");
    }
  }
  while (std::getline(f, line)) {
    ++line_no;
    if (Trim(line).empty()) continue;
    std::stringstream ss(line);
    std::string cell;
    double v[kColumnCount];
    int i = 0;
    while (std::getline(ss, cell, ',')) {
      if (i >= kColumnCount) throw InputError(path, line_no, "", "more than 9 columns");
      const std::string t = Trim(cell);
      std::size_t used = 0;
      try {
        v[i] = std::stod(t, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      // NaN and infinities parse (and make a fault when played); words do not.
      if (t.empty() || used != t.size()) {
        throw InputError(path, line_no, kColumns[i], "'" + t + "' is not a number");
      }
      ++i;
    }
    if (i != kColumnCount) throw InputError(path, line_no, "", "expected 9 columns");
    if (!(v[8] >= 0 && v[8] <= 4294967295.0) ||
        v[8] != static_cast<double>(static_cast<std::uint64_t>(v[8]))) {
      throw InputError(path, line_no, "buttons", "expected an integer bit mask");
    }
    RawDeviceSample s;
    s.p_D = Eigen::Vector3d(v[0], v[1], v[2]);
    s.q_D = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
    s.gripper = v[7];
    s.buttons = static_cast<std::uint32_t>(v[8]);
    s.sample_step = rows_.size();
    rows_.push_back(s);
  }
  if (rows_.empty()) throw InputError(path, line_no, "", "no rows after the header");
}

DeviceSample PlaybackDevice::Read(std::uint64_t step) {
  const RawDeviceSample& row = rows_[std::min<std::uint64_t>(step, rows_.size() - 1)];
  DeviceFault fault = DeviceFault::kNone;
  bool resumed = false;
  const RawDeviceSample& s = guard_.Step(&row, &fault, &resumed);
  DeviceSample out;
  out.X_WT.linear() = s.q_D.normalized().toRotationMatrix();
  out.X_WT.translation() = s.p_D;
  out.gripper = s.gripper;
  out.buttons = s.buttons;
  out.fault = fault;
  return out;
}

}  // namespace microdex::station
