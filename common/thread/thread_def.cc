#include "common/thread/thread_def.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/base/yaml_reader.h"

namespace microdex::thread {
namespace {

void Require(bool ok, const char* field, const std::string& expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
}

bool Finite(double value) { return std::isfinite(value); }

}  // namespace

const char* IntegratorName(Integrator integrator) {
  switch (integrator) {
    case Integrator::kSemiImplicitEuler:
      return "semi-implicit-euler";
    case Integrator::kLinearlyImplicitEuler:
      return "linearly-implicit-euler";
  }
  return "unknown";
}

Integrator ParseIntegrator(const std::string& name) {
  if (name == "semi-implicit-euler") return Integrator::kSemiImplicitEuler;
  if (name == "linearly-implicit-euler") return Integrator::kLinearlyImplicitEuler;
  throw std::invalid_argument(
      "integrator: expected semi-implicit-euler or linearly-implicit-euler, got '" + name + "'");
}

void ThreadDef::Validate() const {
  Require(num_nodes >= 3 && num_nodes <= 100000, "num_nodes", "an integer in [3, 100000]");
  Require(Finite(length_m) && length_m > 0.0 && length_m <= 100.0, "length_m",
          "a length in (0, 100] m");
  const double link_m = length_m / (num_nodes - 1);
  Require(Finite(diameter_m) && diameter_m > 0.0 && diameter_m < 10.0 * link_m, "diameter_m",
          "a positive diameter below 10 link lengths");
  Require(Finite(youngs_modulus_Pa) && youngs_modulus_Pa > 0.0, "youngs_modulus_Pa",
          "a positive modulus in Pa");
  Require(Finite(shear_modulus_Pa) && shear_modulus_Pa > 0.0, "shear_modulus_Pa",
          "a positive modulus in Pa");
  Require(Finite(density_kg_per_m3) && density_kg_per_m3 > 0.0, "density_kg_per_m3",
          "a positive density in kg/m^3");
  Require(Finite(stretch_stiffness_N_per_m) && stretch_stiffness_N_per_m >= 0.0,
          "stretch_stiffness_N_per_m", "0 (derived) or a positive stiffness in N/m");
  Require(Finite(bend_stiffness_N_m) && bend_stiffness_N_m >= 0.0, "bend_stiffness_N_m",
          "0 (derived) or a positive stiffness in N m/rad");
  Require(Finite(twist_stiffness_N_m) && twist_stiffness_N_m >= 0.0, "twist_stiffness_N_m",
          "0 (derived) or a positive stiffness in N m/rad");
  Require(Finite(node_mass_kg) && node_mass_kg >= 0.0, "node_mass_kg",
          "0 (derived) or a positive mass in kg");
  Require(Finite(mass_scale) && mass_scale > 0.0, "mass_scale", "a positive factor");
  Require(Finite(twist_coupling_N) && twist_coupling_N >= 0.0, "twist_coupling_N",
          "a non-negative force in N/rad");
  Require(Finite(drag_N_s_per_m2) && drag_N_s_per_m2 >= 0.0, "drag_N_s_per_m2",
          "a non-negative drag in N s/m^2");
  Require(Finite(twist_drag_N_m_s) && twist_drag_N_m_s >= 0.0, "twist_drag_N_m_s",
          "a non-negative damping in N m s/rad");
  Require(Finite(contact_damping_N_s_per_m) && contact_damping_N_s_per_m >= 0.0,
          "contact_damping_N_s_per_m", "a non-negative damping in N s/m");
  Require(Finite(contact_force_N) && contact_force_N >= 0.0, "contact_force_N",
          "a non-negative force in N");
  Require(Finite(contact_decay_m) && contact_decay_m > 0.0, "contact_decay_m",
          "a positive length in m");
  Require(Finite(contact_cutoff_m) && contact_cutoff_m > 0.0 && contact_cutoff_m < link_m,
          "contact_cutoff_m", "a positive length below the link length");
  Require(Finite(guard_fraction) && guard_fraction >= 0.0 && guard_fraction <= 1.0,
          "guard_fraction", "a fraction in [0, 1]");
  Require(Finite(strain_limit) && strain_limit >= 0.0 && strain_limit < 1.0, "strain_limit",
          "0 (off) or a fraction in (0, 1)");
  Require(gravity_m_per_s2.allFinite() && gravity_m_per_s2.norm() < 1e3, "gravity_m_per_s2",
          "a finite acceleration below 1000 m/s^2");
  Require(Finite(time_step_s) && time_step_s > 0.0 && time_step_s <= 0.1, "time_step_s",
          "a time step in (0, 0.1] s");
  Require(max_grasps >= 1 && max_grasps <= 64, "max_grasps", "an integer in [1, 64]");
  Require(max_contacts >= 0, "max_contacts", "0 (automatic) or a positive capacity");
  Require(exact_contact_pairs >= 0 && exact_contact_pairs <= 1024, "exact_contact_pairs",
          "0 (diagonal bound only) to 1024");
  Require(
      Finite(friction_coefficient) && friction_coefficient >= 0.0 && friction_coefficient <= 10.0,
      "friction_coefficient", "a coefficient in [0, 10]");
  Require(Finite(object_friction_coefficient) && object_friction_coefficient >= 0.0 &&
              object_friction_coefficient <= 10.0,
          "object_friction_coefficient", "a coefficient in [0, 10]");
  Require(friction_contacts >= 0 && friction_contacts <= 1024, "friction_contacts",
          "0 (no friction) to 1024");
  Require(friction_self_contacts >= 0 && friction_self_contacts <= 1024, "friction_self_contacts",
          "0 (friction on objects only) to 1024");
}

ThreadDef StiffNylon10_0() {
  ThreadDef def;
  def.name = "stiff-nylon-10-0";
  def.num_nodes = 65;
  def.length_m = 0.03;
  def.diameter_m = 25e-6;
  def.youngs_modulus_Pa = 3.0e9;
  def.shear_modulus_Pa = 1.1e9;
  def.density_kg_per_m3 = 1140.0;
  def.drag_N_s_per_m2 = 3e-3;
  def.twist_drag_N_m_s = 1e-12;
  def.contact_damping_N_s_per_m = 1e-5;
  def.contact_force_N = 2e-3;
  def.contact_decay_m = 2.5e-6;
  def.contact_cutoff_m = 12.5e-6;
  def.twist_coupling_N = 1e-5;
  def.exact_contact_pairs = 64;
  def.friction_coefficient = 0.2;  // nylon on nylon 0.15-0.25 (ThreadDef)
  def.object_friction_coefficient = 0.2;
  // Implicit thread-on-thread friction for the 16 contacts that carry the most force; the
  // others take the contact projection's position-level friction. With 64, the two friction
  // columns per contact dominate the tight phases of a tie at 385 nodes (tick p99 1.15-1.42
  // against 0.69-1.19 ms with 16); the 60 cases of the tie matrix tie and hold with 64, 32 or
  // 16 (common/thread/README.md, "Fourth round"). Object contacts keep theirs (a capstan wrap
  // needs all of them).
  def.friction_self_contacts = 16;
  return def;
}

ThreadDef SoftSilk() {
  ThreadDef def;
  def.name = "soft-silk";
  def.num_nodes = 65;
  def.length_m = 0.05;
  def.diameter_m = 70e-6;
  def.youngs_modulus_Pa = 0.5e9;
  def.shear_modulus_Pa = 0.1e9;
  def.density_kg_per_m3 = 1300.0;
  def.drag_N_s_per_m2 = 3e-3;
  def.twist_drag_N_m_s = 1e-11;
  def.contact_damping_N_s_per_m = 1e-5;
  def.contact_force_N = 5e-3;
  def.contact_decay_m = 7e-6;
  def.contact_cutoff_m = 35e-6;
  def.twist_coupling_N = 1e-5;
  def.exact_contact_pairs = 64;
  def.friction_coefficient = 0.3;  // braided silk, rougher than a monofilament (ThreadDef)
  def.object_friction_coefficient = 0.3;
  return def;
}

ThreadDef Necklace() {
  ThreadDef def;
  def.name = "necklace";
  def.num_nodes = 65;
  def.length_m = 0.4;
  def.diameter_m = 3e-3;
  def.youngs_modulus_Pa = 1.0e9;
  def.shear_modulus_Pa = 0.4e9;
  def.density_kg_per_m3 = 2500.0;
  // Beads on a string: the string stretches little, the chain bends and twists freely.
  def.bend_stiffness_N_m = 1e-6;
  def.twist_stiffness_N_m = 1e-6;
  def.drag_N_s_per_m2 = 1e-2;
  def.twist_drag_N_m_s = 1e-8;
  def.contact_damping_N_s_per_m = 1e-2;
  def.contact_force_N = 0.5;
  def.contact_decay_m = 0.3e-3;
  def.contact_cutoff_m = 1.5e-3;
  def.twist_coupling_N = 0.0;
  // Beads rubbing on beads and on objects: 0.3, a judgement between lubricated (0.2-0.3) and
  // clean (0.5-0.7) glass on metal in engineering charts (e.g. Schneider's reference chart).
  def.exact_contact_pairs = 64;
  def.friction_coefficient = 0.3;
  def.object_friction_coefficient = 0.3;
  return def;
}

ThreadDef ThreadPreset(const std::string& name) {
  if (name == "stiff-nylon-10-0") return StiffNylon10_0();
  if (name == "soft-silk") return SoftSilk();
  if (name == "necklace") return Necklace();
  throw std::invalid_argument(
      "thread preset: expected stiff-nylon-10-0, soft-silk or necklace, got '" + name + "'");
}

ThreadDef LoadThreadDef(const std::string& path) {
  const YamlSection thread = YamlReader(path).Root().Map("thread");
  thread.CheckNoUnknownKeys({"base",
                             "name",
                             "num_nodes",
                             "length_m",
                             "diameter_m",
                             "youngs_modulus_Pa",
                             "shear_modulus_Pa",
                             "density_kg_per_m3",
                             "stretch_stiffness_N_per_m",
                             "bend_stiffness_N_m",
                             "twist_stiffness_N_m",
                             "node_mass_kg",
                             "mass_scale",
                             "twist_coupling_N",
                             "drag_N_s_per_m2",
                             "twist_drag_N_m_s",
                             "contact_damping_N_s_per_m",
                             "contact_force_N",
                             "contact_decay_m",
                             "contact_cutoff_m",
                             "guard_fraction",
                             "strain_limit",
                             "gravity_m_per_s2",
                             "integrator",
                             "time_step_s",
                             "max_grasps",
                             "max_contacts",
                             "exact_contact_pairs",
                             "friction_coefficient",
                             "object_friction_coefficient",
                             "friction_contacts",
                             "friction_self_contacts"});
  ThreadDef def;
  // An empty base starts from the defaults.
  if (!thread.String("base", "").empty()) def = thread.Enum("base", &ThreadPreset, def);
  def.name = thread.String("name", def.name);
  def.num_nodes = thread.Int("num_nodes", def.num_nodes);
  def.length_m = thread.FiniteDouble("length_m", def.length_m);
  def.diameter_m = thread.FiniteDouble("diameter_m", def.diameter_m);
  def.youngs_modulus_Pa = thread.FiniteDouble("youngs_modulus_Pa", def.youngs_modulus_Pa);
  def.shear_modulus_Pa = thread.FiniteDouble("shear_modulus_Pa", def.shear_modulus_Pa);
  def.density_kg_per_m3 = thread.FiniteDouble("density_kg_per_m3", def.density_kg_per_m3);
  def.stretch_stiffness_N_per_m =
      thread.FiniteDouble("stretch_stiffness_N_per_m", def.stretch_stiffness_N_per_m);
  def.bend_stiffness_N_m = thread.FiniteDouble("bend_stiffness_N_m", def.bend_stiffness_N_m);
  def.twist_stiffness_N_m = thread.FiniteDouble("twist_stiffness_N_m", def.twist_stiffness_N_m);
  def.node_mass_kg = thread.FiniteDouble("node_mass_kg", def.node_mass_kg);
  def.mass_scale = thread.FiniteDouble("mass_scale", def.mass_scale);
  def.twist_coupling_N = thread.FiniteDouble("twist_coupling_N", def.twist_coupling_N);
  def.drag_N_s_per_m2 = thread.FiniteDouble("drag_N_s_per_m2", def.drag_N_s_per_m2);
  def.twist_drag_N_m_s = thread.FiniteDouble("twist_drag_N_m_s", def.twist_drag_N_m_s);
  def.contact_damping_N_s_per_m =
      thread.FiniteDouble("contact_damping_N_s_per_m", def.contact_damping_N_s_per_m);
  def.contact_force_N = thread.FiniteDouble("contact_force_N", def.contact_force_N);
  def.contact_decay_m = thread.FiniteDouble("contact_decay_m", def.contact_decay_m);
  def.contact_cutoff_m = thread.FiniteDouble("contact_cutoff_m", def.contact_cutoff_m);
  def.guard_fraction = thread.FiniteDouble("guard_fraction", def.guard_fraction);
  def.strain_limit = thread.FiniteDouble("strain_limit", def.strain_limit);
  def.time_step_s = thread.FiniteDouble("time_step_s", def.time_step_s);
  def.max_grasps = thread.Int("max_grasps", def.max_grasps);
  def.max_contacts = thread.Int("max_contacts", def.max_contacts);
  def.exact_contact_pairs = thread.Int("exact_contact_pairs", def.exact_contact_pairs);
  def.friction_coefficient = thread.FiniteDouble("friction_coefficient", def.friction_coefficient);
  def.object_friction_coefficient =
      thread.FiniteDouble("object_friction_coefficient", def.object_friction_coefficient);
  def.friction_contacts = thread.Int("friction_contacts", def.friction_contacts);
  def.friction_self_contacts = thread.Int("friction_self_contacts", def.friction_self_contacts);
  def.gravity_m_per_s2 = thread.Vec3("gravity_m_per_s2", def.gravity_m_per_s2);
  def.integrator = thread.Enum("integrator", &ParseIntegrator, def.integrator);
  try {
    def.Validate();
  } catch (const std::invalid_argument& e) {
    thread.FailInvalid(e);
  }
  return def;
}

}  // namespace microdex::thread
