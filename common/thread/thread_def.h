#pragma once
// Description of a suture thread (thesis chapter 5), in SI units, with its one validation
// point, the three named parameter sets and a YAML loader.

#include <Eigen/Core>
#include <string>

namespace microdex::thread {

// Which time integrator StepThread uses.
enum class Integrator {
  kSemiImplicitEuler,      // (5.2), the thesis's scheme: explicit forces, symplectic update.
  kLinearlyImplicitEuler,  // One Newton step of backward Euler, block-banded solve.
};

const char* IntegratorName(Integrator integrator);
// Parses "semi-implicit-euler" / "linearly-implicit-euler"; throws std::invalid_argument.
Integrator ParseIntegrator(const std::string& name);

struct ThreadDef {
  // Name of the parameter set (free text, for reports).
  std::string name = "unnamed";

  // Geometry. The thread is a chain of num_nodes nodes and num_nodes - 1 links of equal rest
  // length length_m / (num_nodes - 1) (thesis Fig. 5.1).
  int num_nodes = 65;
  double length_m = 0.03;
  double diameter_m = 25e-6;

  // Material. Stiffness constants are derived per link from the continuum: stretch
  // kappa_s = E A / r (5.4), bend kappa_b = E I / r (torque per radian of turning angle, (5.5)),
  // twist kappa_d = G J / r (5.6), with A = pi d^2 / 4, I = pi d^4 / 64, J = 2 I, r the link
  // rest length.
  double youngs_modulus_Pa = 3.0e9;
  double shear_modulus_Pa = 1.1e9;
  double density_kg_per_m3 = 1140.0;

  // Direct overrides (used when > 0) of the derived per-link constants and node mass; the
  // stability study sweeps these.
  double stretch_stiffness_N_per_m = 0.0;  // kappa_s of (5.4)
  double bend_stiffness_N_m = 0.0;         // kappa_b of (5.5), N m / rad
  double twist_stiffness_N_m = 0.0;        // kappa_d of (5.6), N m / rad
  double node_mass_kg = 0.0;               // m_i of (5.1)

  // Node masses (and inertias) are multiplied by this. 1 is the physical thread; a haptic
  // scene may make the thread heavier so that its dynamics are felt.
  double mass_scale = 1.0;

  // Coupling of link twist into an out-of-plane force at a bend (5.7), N per radian of twist.
  double twist_coupling_N = 0.0;

  // Damping (5.8). Free damping per unit length of thread (viscous drag of the surrounding
  // fluid, N s / m^2: a node carries its share of thread length), free torsional damping per
  // node (N m s / rad), and extra damping of a node while it is in contact (N s / m).
  double drag_N_s_per_m2 = 3e-3;
  double twist_drag_N_m_s = 1e-12;
  double contact_damping_N_s_per_m = 0.0;

  // Contact reaction (5.9): f = contact_force_N * (exp(-gap / decay) - exp(-cutoff / decay))
  // for gap < cutoff, where gap is the surface distance between two links (or a link and an
  // object). Negative gap (overlap) makes the force grow exponentially.
  double contact_force_N = 1e-3;
  double contact_decay_m = 2.5e-6;
  double contact_cutoff_m = 12.5e-6;

  // Contact projection after each step (ProjectContacts, not in the thesis): centreline
  // distance between non-adjacent links is projected back to at least this fraction of the
  // diameter (link surface to object: at least (fraction - 1) radius), with Coulomb friction.
  // 0 disables it (the thesis has no hard contact).
  double guard_fraction = 0.97;

  // Strain limiting after each linearly implicit step (not in the thesis): link lengths are
  // projected into [1 - strain_limit, 1 + strain_limit] times their rest length inside the
  // contact projection, by a direct (tridiagonal) mass-weighted solve of all link lengths
  // (strain_band.h). One linearised step that rotates a stiff link far
  // lengthens it (to second order in the rotation), which the stability study measured as
  // strain > 10 % at 1 ms; 0 disables it. The baseline (5.2) is left as the thesis has it.
  double strain_limit = 0.05;

  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d(0.0, 0.0, -9.81);

  Integrator integrator = Integrator::kLinearlyImplicitEuler;
  double time_step_s = 1e-3;

  // Capacities, fixed at model build (nothing grows during a step).
  int max_grasps = 4;
  int max_contacts = 0;  // 0: 16 per link

  // Self contacts whose stiffness and damping enter the linearly implicit step exactly, as the
  // relative pair terms (h c + h^2 k) (g (x) n)(g (x) n)^T (a low-rank update of the banded
  // solve, by Woodbury's identity); the deepest contacts first. Contacts beyond this count get
  // the per-node diagonal bound 2 |g_i| k n n^T, which dominates the pair term but anchors the
  // nodes in absolute terms (a tight knot then resists being moved as a whole). 0: bound only.
  int exact_contact_pairs = 64;

  // Coulomb friction (not in the thesis, whose "friction" (5.8) is viscous damping): the
  // tangential impulse of a contact over a step is at most mu * f_n * h, f_n the normal force
  // (5.9) at the start of the step; the contact sticks when the impulse that stops its relative
  // tangential motion is inside that cone. Thread on thread and thread on objects (tools, the
  // needle, tissue). 0: frictionless. Literature: nylon on nylon 0.15-0.25 (dry, engineering
  // tables, e.g. Roymech "Coefficients of friction"); surgical sutures on skin-like surfaces
  // were measured by the capstan method by Zhang, Ren, Zeng & van der Heide, Friction 7 (2019)
  // 87-98, doi:10.1007/s40544-017-0140-3. Braided silk is rougher than a monofilament (braided
  // sutures hold knots with fewer throws): 0.3 for silk. The default is the nylon's 0.2, also
  // used on objects (steel instruments, tissue: a working value, not taken from a table); the
  // presets set their own.
  double friction_coefficient = 0.2;
  double object_friction_coefficient = 0.2;
  // Contacts (self first, deepest first, then object contacts) that get friction in one step;
  // each adds two columns to the linearly implicit step's low-rank solve. 0: none.
  int friction_contacts = 64;
  // Of those, at most this many self contacts (the deepest); the self contacts beyond it take
  // only the contact projection's position-level friction, and the object contacts keep the
  // rest of friction_contacts. 0: friction on objects only.
  int friction_self_contacts = 64;

  // Throws std::invalid_argument for the first bad field, whose message starts with the field
  // name followed by ': ' (e.g. `diameter_m: expected a positive diameter below 10 link lengths`).
  void Validate() const;
};

// Microsurgery: USP 10-0 monofilament nylon, diameter 25 um, E = 3 GPa, 30 mm segment.
ThreadDef StiffNylon10_0();
// Braided 6-0 silk: diameter 70 um, soft in bending (effective E of the braid 0.5 GPa).
ThreadDef SoftSilk();
// A bead necklace: diameter 3 mm, 0.4 m, heavy, nearly no bending stiffness.
ThreadDef Necklace();
// By name: "stiff-nylon-10-0", "soft-silk", "necklace"; throws std::invalid_argument.
ThreadDef ThreadPreset(const std::string& name);

// Reads a thread parameter file (assets/scenes/thread_*.yaml: a map `thread:`, optionally
// starting from a preset `base`) and validates it. Throws microdex::InputError
// "FILE:LINE: thread.FIELD: reason" (common/base/input_error.h).
ThreadDef LoadThreadDef(const std::string& path);

}  // namespace microdex::thread
