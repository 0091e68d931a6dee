#include "io/case_file.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "io/csv.hpp"
#include "io/toml_section.hpp"
#include "models/registry.hpp"

namespace cohdem {

namespace {


/// Applies one --set override "a.b.c=value" (array-of-table elements by index or by name:
/// "wall.floor.velocity=[0,0,1]" or "insert.0.count=100").
void apply_override(toml::table& root, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set", 0, kv, "expected key=value, e.g. --set simulation.dt=1e-6");
  const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
  std::vector<std::string> parts;
  {
    std::stringstream ss(key);
    std::string p;
    while (std::getline(ss, p, '.')) parts.push_back(p);
  }
  // Parse the value as TOML; a bare word is taken as a string.
  toml::table vt;
  try {
    vt = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    try {
      vt = toml::parse("v = \"" + value + "\"");
    } catch (const toml::parse_error& e) {
      throw InputError("--set", 0, key, "cannot read value '" + value + "'");
    }
  }
  toml::node* cur = &root;
  for (size_t k = 0; k + 1 < parts.size(); ++k) {
    const std::string& p = parts[k];
    if (auto* t = cur->as_table()) {
      toml::node* next = t->get(p);
      if (!next) {
        t->insert(p, toml::table{});
        next = t->get(p);
      }
      cur = next;
    } else if (auto* a = cur->as_array()) {
      toml::node* found = nullptr;
      const bool numeric = !p.empty() && std::all_of(p.begin(), p.end(), ::isdigit);
      if (numeric && std::stoul(p) < a->size()) found = a->get(std::stoul(p));
      if (!numeric)
        for (auto& e : *a)
          if (auto* et = e.as_table(); et && et->get("name") && et->get("name")->value_exact<std::string>() == p)
            found = &e;
      if (!found) throw InputError("--set", 0, key, "no element '" + p + "' in array '" + parts[k - 1] + "'");
      cur = found;
    } else {
      throw InputError("--set", 0, key, "'" + p + "' is not a table");
    }
  }
  auto* t = cur->as_table();
  if (!t) throw InputError("--set", 0, key, "cannot set a key inside a non-table");
  t->insert_or_assign(parts.back(), *vt.get("v"));
}

SizeDistribution read_size(Section s) {
  SizeDistribution d;
  const std::string kind = s.str("distribution", std::nullopt, {"constant", "uniform", "gaussian", "list"});
  if (kind == "constant") {
    d.kind = SizeDistribution::Kind::Constant;
    d.r = s.num("radius", std::nullopt, 0, kInf, true, "m");
  } else if (kind == "uniform") {
    d.kind = SizeDistribution::Kind::Uniform;
    d.rmin = s.num("min", std::nullopt, 0, kInf, true, "m");
    d.rmax = s.num("max", std::nullopt, d.rmin, kInf, false, "m");
  } else if (kind == "gaussian") {
    d.kind = SizeDistribution::Kind::Gaussian;
    d.mean = s.num("mean", std::nullopt, 0, kInf, true, "m");
    d.stddev = s.num("std", std::nullopt, 0, kInf, true, "m");
    d.bound = s.num("bound", 0.1, 0, 1, true, "(fraction of the mean)");
  } else {
    d.kind = SizeDistribution::Kind::List;
    d.radii = s.numbers("radii", std::nullopt);
    d.weights = s.numbers("weights", std::vector<double>(d.radii.size(), 1.0));
    if (d.radii.empty()) s.fail("radii", "expected at least one radius");
    if (d.weights.size() != d.radii.size()) s.fail("weights", "expected one weight per radius");
    for (double r : d.radii)
      if (!(r > 0)) s.fail("radii", "radii must be > 0 m");
    for (double w : d.weights)
      if (!(w >= 0)) s.fail("weights", "weights must be >= 0");
  }
  s.finish();
  return d;
}

Region read_region(Section s, const std::string& name) {
  Region r;
  r.name = name;
  const std::string kind = s.str("type", std::nullopt, {"box", "cylinder", "annulus"});
  if (kind == "box") {
    r.kind = Region::Kind::Box;
    r.lo = s.vec3("lo", std::nullopt);
    r.hi = s.vec3("hi", std::nullopt);
    for (int d = 0; d < 3; ++d)
      if (!(r.hi[d] > r.lo[d])) s.fail("hi", "each component of hi must exceed lo");
  } else {
    r.kind = kind == "cylinder" ? Region::Kind::Cylinder : Region::Kind::Annulus;
    const Vec3 c = s.vec3("center", Vec3{0, 0, 0});
    r.center = c;
    if (r.kind == Region::Kind::Annulus) {
      r.r_in = s.num("r_inner", std::nullopt, 0, kInf, true, "m");
      r.r_out = s.num("r_outer", std::nullopt, r.r_in, kInf, true, "m");
    } else {
      r.r_out = s.num("radius", std::nullopt, 0, kInf, true, "m");
    }
    r.zmin = s.num("zmin", std::nullopt, -kInf, kInf, false, "m");
    r.zmax = s.num("zmax", std::nullopt, r.zmin, kInf, true, "m");
  }
  s.finish();
  return r;
}

/// A number, or a schedule table `{ times = [...], values = [...], period = P }` (piecewise
/// linear in time, repeated every P s when P > 0); values checked against [lo, hi].
Schedule read_schedule(Section& s, const std::string& key, double lo, double hi, const char* unit) {
  const toml::node* n = s.node(key);
  if (n && n->is_table()) {
    Section t = *s.table(key);
    Schedule sc;
    sc.times = t.numbers("times", std::nullopt);
    sc.values = t.numbers("values", std::nullopt);
    sc.period = t.num("period", 0.0, 0, kInf, false, "s");
    t.finish();
    if (sc.times.empty()) t.fail("times", "expected at least one time");
    if (sc.values.size() != sc.times.size()) t.fail("values", "expected one value per time");
    for (size_t k = 1; k < sc.times.size(); ++k)
      if (!(sc.times[k] > sc.times[k - 1])) t.fail("times", "times must increase");
    for (double v : sc.values)
      if (v < lo || v > hi) t.fail("values", "value " + std::to_string(v) + " out of range " + unit);
    if (sc.period > 0 && sc.period < sc.times.back() - sc.times.front())
      t.fail("period", "the period must be at least times[last] - times[0]");
    return sc;
  }
  if (n && !n->is_number()) s.fail(key, std::string("expected a number (") + unit + ") or a schedule table { times, values, period }");
  return Schedule::constant(s.num(key, std::nullopt, lo, hi, false, unit));
}

/// A path named in a case file, relative to the case file's folder (to the working folder for
/// an embedded case or case text).
std::string beside_case(const std::string& case_file, const std::string& rel) {
  const std::filesystem::path r(rel);
  if (r.is_absolute() || case_file.empty() || case_file.front() == '<') return rel;
  return (std::filesystem::path(case_file).parent_path() / r).string();
}

/// The particles of a [[particles]] file (see docs/case-file.md): a numeric CSV table
/// (io/csv.hpp: a header naming the columns, '#' comment lines, numbers read correctly
/// rounded, errors naming the file, line and column) with columns x, y, z and radius, and
/// optionally vx, vy, vz, wx, wy, wz (zero when absent); other columns are ignored.
void read_particle_file(const std::string& path, const Section& s, const ExplicitParticle& proto,
                        std::vector<ExplicitParticle>& out) {
  if (!std::ifstream(path)) s.fail("file", "cannot open particle file '" + path + "'");
  const CsvTable t = CsvTable::read(path);
  if (t.num_rows() == 0) s.fail("file", "particle file '" + path + "' has no particle rows");
  static const char* const kCols[10] = {"x", "y", "z", "radius", "vx", "vy", "vz", "wx", "wy", "wz"};
  const std::vector<double>* col[10] = {};
  for (int k = 0; k < 10; ++k) {
    if (t.has(kCols[k])) col[k] = &t.column(kCols[k]);
    else if (k < 4)
      throw InputError(path, 1, kCols[k], "missing column in the header (required: x, y, z, radius; optional: vx, vy, "
                                          "vz, wx, wy, wz)");
  }
  out.reserve(out.size() + t.num_rows());
  for (size_t r = 0; r < t.num_rows(); ++r) {
    double v[10] = {};
    for (int k = 0; k < 10; ++k) {
      if (!col[k]) continue;
      v[k] = (*col[k])[r];
      if (!std::isfinite(v[k])) throw InputError(path, t.line_of_row(r), kCols[k], "expected a finite number");
    }
    if (!(v[3] > 0)) throw InputError(path, t.line_of_row(r), "radius", "expected a number > 0 m");
    ExplicitParticle p = proto;
    p.x = {v[0], v[1], v[2]};
    p.radius = v[3];
    p.v = {v[4], v[5], v[6]};
    p.omega = {v[7], v[8], v[9]};
    out.push_back(p);
  }
}

int material_index(const Case& c, Section& s, const std::string& key) {
  const std::string name = s.str(key, std::nullopt);
  for (size_t i = 0; i < c.materials.size(); ++i)
    if (c.materials[i].name == name) return int(i);
  std::vector<std::string> names;
  for (const auto& m : c.materials) names.push_back(m.name);
  s.fail(key, "unknown material '" + name + "'; defined materials: " + Section::join(names));
}

void read_contact_params(Section& s, ParamSet& p, const std::vector<ParamSpec>& specs,
                         const std::set<std::string>& skip, const std::string& file, const std::string& model) {
  std::vector<std::string> valid;
  for (const auto& sp : specs) valid.push_back(sp.name);
  for (const std::string& k : s.keys()) {
    if (skip.count(k)) continue;
    s.use(k);
    if (std::find(valid.begin(), valid.end(), k) == valid.end())
      s.fail(k, "not a parameter of contact model '" + model + "'; its parameters are: " + Section::join(valid));
    const toml::node* n = s.node(k);
    double v;
    if (auto d = n->value_exact<double>()) v = *d;
    else if (auto i = n->value_exact<int64_t>()) v = double(*i);
    else if (auto b = n->value_exact<bool>()) v = *b ? 1.0 : 0.0;
    else s.fail(k, "expected a number");
    p.set(k, v, {file, line_of(*n), s.path()});
  }
}

Case parse(toml::table& root, const std::string& file) {
  Case c;
  c.file = file;
  Section top(root, "", file);

  if (auto s = top.table("case")) {
    c.name = s->str("name", "");
    s->str("units", "SI", {"SI"});
    s->str("description", "");
    s->finish();
  }

  // [simulation]
  {
    Section s = *top.table("simulation", true);
    c.cfg.dt = s.num("dt", std::nullopt, 0, kInf, true, "s");
    c.dt_line = s.node("dt") ? line_of(*s.node("dt")) : s.line();
    c.duration = s.num("duration", std::nullopt, 0, kInf, false, "s");
    c.cfg.gravity = s.vec3("gravity", Vec3{0, 0, -9.81});
    c.cfg.skin = s.num("skin", 0.0, 0, kInf, false, "m");
    c.cfg.threads = int(s.integer("threads", 0));
    c.cfg.sort_every = int(s.integer("sort_every", 20));
    // The local check before a list build (NeighborList::recheck): blocks of this many
    // interaction cutoffs; 0 turns it off.
    c.cfg.local_rebuild = s.num("local_rebuild", 2.0, 0, 1000, false, "cutoffs");
    if (c.cfg.local_rebuild > 0 && c.cfg.local_rebuild < 1)
      s.fail("local_rebuild", "expected 0 (off) or a block edge of at least 1 interaction cutoff");
    const auto pmin = s.integer("parallel_min", 4000);
    if (pmin < 0) s.fail("parallel_min", "expected a particle count >= 0");
    c.cfg.parallel_min = long(pmin);
    // Several steps in one sweep of the force loop (System::step_sweep; the same results).
    const bool pairs = s.boolean("pair_steps", true);
    c.cfg.pair_min = long(s.integer("pair_min", 65536, 1));
    if (!pairs) c.cfg.pair_min = -1;
    const auto sweep = s.integer("sweep_steps", 4, 2);
    if (sweep > 4) s.fail("sweep_steps", "expected 2, 3 or 4 steps in one sweep of the force loop");
    c.cfg.sweep_steps = int(sweep);
    c.cfg.sweep_min = long(s.integer("sweep_min", 65536, 1));
    c.cfg.sweep_tune = s.boolean("sweep_tune", true);
    c.seed = uint64_t(s.integer("seed", 1));
    c.audit_velocity = s.num("audit_velocity", 0.0, 0, kInf, false, "m/s");
    s.finish();
  }
  // [domain]
  top.use("domain");
  if (const toml::node* dn = root.get("domain"); dn && dn->is_table()) {
    Section s(*dn->as_table(), "domain", file);
    c.cfg.domain.lo = s.vec3("lo", Vec3{0, 0, 0});
    c.cfg.domain.hi = s.vec3("hi", Vec3{0, 0, 0});
    s.use("periodic");
    if (const toml::node* pn = s.node("periodic")) {
      const toml::array* a = pn->as_array();
      if (!a || a->size() != 3) s.fail("periodic", "expected [bool, bool, bool] for x, y, z");
      for (size_t d = 0; d < 3; ++d) {
        auto b = a->get(d)->value_exact<bool>();
        if (!b) s.fail("periodic", "expected [bool, bool, bool] for x, y, z");
        c.cfg.domain.periodic[d] = *b;
        if (*b && !(c.cfg.domain.hi[int(d)] > c.cfg.domain.lo[int(d)]))
          s.fail("hi", std::string("periodic in ") + "xyz"[d] + ": hi must exceed lo");
      }
    }
    s.finish();
  }

  // [thermal] (heat conduction and thermal expansion; docs/packed-beds.md)
  if (auto s = top.table("thermal")) {
    c.thermal.enabled = true;
    c.cfg.initial_temperature = s->num("initial_temperature", 293.15, 0, kInf, true, "K");
    c.thermal.time_scale = s->num("time_scale", 1.0, 0, kInf, true, "");
    c.thermal.expansion = s->boolean("expansion", true);
    c.thermal.contact_radius = s->str("contact_radius", "model", {"model", "hertz_force"}) == "model"
                                   ? ThermalSettings::SpotRadius::Model
                                   : ThermalSettings::SpotRadius::HertzForce;
    s->finish();
  }
  std::vector<int> material_line;

  // [[material]]
  for (Section s : top.tables("material")) {
    Material m;
    m.name = s.str("name", std::nullopt);
    for (const auto& o : c.materials)
      if (o.name == m.name) s.fail("name", "material '" + m.name + "' defined twice");
    m.density = s.num("density", 0.0, 0, kInf, false, "kg/m^3");
    m.E = s.num("youngs_modulus", 0.0, 0, kInf, false, "Pa");
    m.nu = s.num("poisson_ratio", 0.25, -1, 0.5, true, "");
    if (m.nu >= 0.5) s.fail("poisson_ratio", "Poisson ratio must be < 0.5");
    m.conductivity = s.num("thermal_conductivity", 0.0, 0, kInf, false, "W/(m K)");
    m.heat_capacity = s.num("heat_capacity", 0.0, 0, kInf, false, "J/(kg K)");
    m.expansion = s.num("thermal_expansion", 0.0, -1e-2, 1e-2, false, "1/K");
    m.T_ref = s.num("reference_temperature", c.cfg.initial_temperature, 0, kInf, true, "K");
    m.E_conduction = s.num("conduction_youngs_modulus", 0.0, 0, kInf, false, "Pa");
    material_line.push_back(s.line());
    s.finish();
    c.materials.push_back(m);
  }
  if (c.materials.empty()) top.fail("material", "at least one [[material]] is required");
  const int nm = int(c.materials.size());

  // [contact]
  {
    Section s = *top.table("contact", true);
    c.model = s.str("model", std::nullopt, contact_model_names());
    c.rolling = s.str("rolling", "none", rolling_model_names());
    auto m = make_contact_model(c.model, c.rolling, file, s.line());
    const auto specs = m->specs();
    ParamSet base;
    base.set_context(file, s.line(), "contact");
    read_contact_params(s, base, specs, {"model", "rolling", "pair"}, file, c.model);
    c.pair_params.assign(size_t(nm) * nm, base);
    for (Section ps : s.tables("pair")) {
      const auto names = ps.strings("materials", std::nullopt);
      if (names.size() != 2) ps.fail("materials", "expected two material names");
      int idx[2];
      for (int q = 0; q < 2; ++q) {
        idx[q] = -1;
        for (int i = 0; i < nm; ++i)
          if (c.materials[i].name == names[q]) idx[q] = i;
        if (idx[q] < 0) ps.fail("materials", "unknown material '" + names[q] + "'");
      }
      ParamSet p = base;
      p.set_context(file, ps.line(), ps.path());
      read_contact_params(ps, p, specs, {"materials"}, file, c.model);
      c.pair_params[size_t(idx[0]) * nm + idx[1]] = p;
      c.pair_params[size_t(idx[1]) * nm + idx[0]] = p;
    }
    s.finish();
    // Validate every pair now (missing/out-of-range parameters are input errors).
    System probe;
    probe.materials = c.materials;
    probe.set_model(std::move(m), c.pair_params);
    // Models built on E* need E on both materials.
    if (c.model == "hertz_mindlin")
      for (const auto& mat : c.materials)
        if (!(mat.E > 0))
          throw InputError(file, 0, "material." + mat.name + ".youngs_modulus",
                           "contact model '" + c.model + "' needs youngs_modulus > 0 for every material");
  }

  // [[wall]]
  for (Section s : top.tables("wall")) {
    Wall w;
    w.name = s.str("name", std::nullopt);
    const std::string type = s.str("type", std::nullopt, {"plane", "cylinder", "annulus"});
    w.material = material_index(c, s, "material");
    w.velocity = s.vec3("velocity", Vec3{});
    w.omega = s.vec3("omega", Vec3{});
    if (auto o = s.table("oscillation")) {
      w.osc_amplitude = o->num("amplitude", std::nullopt, 0, kInf, false, "m");
      w.osc_frequency = o->num("frequency", std::nullopt, 0, kInf, true, "Hz");
      w.osc_dir = normalized(o->vec3("direction", Vec3{0, 0, 1}));
      if (norm(w.osc_dir) == 0) o->fail("direction", "direction must be non-zero");
      o->finish();
    }
    const std::string control = s.str("control", "prescribed", {"prescribed", "servo", "spring"});
    WallThermal wt;
    if (s.has("temperature")) {
      if (!c.thermal.enabled) s.fail("temperature", "a wall temperature needs a [thermal] table");
      wt.fixed = true;
      wt.temperature = read_schedule(s, "temperature", 1e-9, kInf, "K");
      if (!(c.materials[w.material].conductivity > 0))
        s.fail("temperature", "a wall at a fixed temperature conducts through its material: give material '" +
                                  c.materials[w.material].name + "' a thermal_conductivity > 0");
    }
    std::vector<Wall> made;
    if (type == "plane") {
      w.shape = WallShape::Plane;
      w.point = s.vec3("point", std::nullopt);
      w.normal = s.vec3("normal", std::nullopt);
      if (norm(w.normal) == 0) s.fail("normal", "normal must be non-zero");
      w.normal = normalized(w.normal);
      w.rmin = s.num("rmin", 0.0, 0, kInf, false, "m");
      w.rmax = s.num("rmax", kInf, w.rmin, kInf, true, "m");
      w.center = s.vec3("center", w.point);
      made.push_back(w);
    } else {
      w.shape = WallShape::Cylinder;
      w.point = s.vec3("point", Vec3{0, 0, 0});
      w.normal = s.vec3("axis", Vec3{0, 0, 1});
      if (norm(w.normal) == 0) s.fail("axis", "axis must be non-zero");
      w.normal = normalized(w.normal);
      w.zmin = s.num("zmin", -kInf, -kInf, kInf, false, "m");
      w.zmax = s.num("zmax", kInf, w.zmin, kInf, true, "m");
      w.center = s.vec3("center", w.point);
      if (type == "cylinder") {
        w.radius = s.num("radius", std::nullopt, 0, kInf, true, "m");
        w.inside = s.str("side", "inside", {"inside", "outside"}) == "inside";
        made.push_back(w);
      } else {
        const double ri = s.num("r_inner", std::nullopt, 0, kInf, true, "m");
        const double ro = s.num("r_outer", std::nullopt, ri, kInf, true, "m");
        Wall a = w, b = w;
        a.name = w.name + "_inner"; a.radius = ri; a.inside = false;
        b.name = w.name + "_outer"; b.radius = ro; b.inside = true;
        made = {a, b};
      }
    }
    for (Wall& m : made) {
      // Rotation must keep the geometry (about the normal of a plane, the axis of a cylinder).
      if (norm(m.omega) > 0 && norm(cross(m.omega, m.normal)) > 1e-12 * norm(m.omega))
        s.fail("omega", "a wall may rotate only about its own normal (plane) or axis (cylinder)");
      if (control != "prescribed") {
        if (m.shape != WallShape::Plane) s.fail("control", "controlled walls must be planes");
        m.control = control == "servo" ? WallControl::Servo : WallControl::Spring;
      }
    }
    if (control != "prescribed") {
      const double t0 = s.num("control_start", 0.0, 0, kInf, false, "s");
      for (Wall& m : made) m.control_start = t0;
    }
    if (control == "servo") {
      const double F = s.num("target_force", std::nullopt, 0, kInf, false, "N");
      const double g = s.num("servo_gain", std::nullopt, 0, kInf, true, "m/(N s)");
      const double vmax = s.num("servo_vmax", kInf, 0, kInf, true, "m/s");
      for (Wall& m : made) { m.target_force = F; m.servo_gain = g; m.servo_vmax = vmax; }
    } else if (control == "spring") {
      const double mass = s.num("mass", std::nullopt, 0, kInf, true, "kg");
      const double k = s.num("spring_k", std::nullopt, 0, kInf, false, "N/m");
      const double pre = s.num("spring_preload", 0.0, -kInf, kInf, false, "N");
      for (Wall& m : made) { m.mass = mass; m.spring_k = k; m.spring_preload = pre; }
    }
    s.finish();
    for (const Wall& o : c.walls)
      if (o.name == w.name) s.fail("name", "wall '" + w.name + "' defined twice");
    for (Wall& m : made) {
      c.walls.push_back(m);
      c.thermal.walls.push_back(wt);
    }
  }

  // [[insert]]
  int nins = 0;
  for (Section s : top.tables("insert")) {
    InsertStep st;
    st.line = s.line();
    st.key = s.path();
    st.spec.species = material_index(c, s, "material");
    if (!(c.materials[st.spec.species].density > 0))
      s.fail("material", "particles need a material with density > 0");
    st.spec.region = read_region(*s.table("region", true), s.path());
    st.spec.size = read_size(*s.table("size", true));
    const bool has_count = s.has("count"), has_frac = s.has("solids_fraction");
    if (has_count == has_frac) s.fail("count", "give exactly one of count or solids_fraction");
    if (has_count) st.spec.count = uint64_t(s.integer("count", std::nullopt, 1));
    if (has_frac) st.spec.solids_fraction = s.num("solids_fraction", std::nullopt, 0, 0.74, true, "");
    st.spec.velocity = s.vec3("velocity", Vec3{});
    st.spec.velocity_jitter = s.num("velocity_jitter", 0.0, 0, kInf, false, "m/s");
    st.spec.max_attempts = int(s.integer("max_attempts", 2000, 1));
    const std::string mode = s.str("mode", "fill", {"fill", "pour"});
    if (mode == "pour") {
      st.pour = true;
      if (!has_count) s.fail("count", "pouring needs a count");
      st.rate = s.num("rate", std::nullopt, 0, kInf, true, "particles/s");
      st.start = s.num("start", 0.0, 0, kInf, false, "s");
      st.interval = s.num("interval", 0.0, 0, kInf, false, "s");
    }
    s.finish();
    c.inserts.push_back(st);
    ++nins;
  }
  // [[particle]]
  for (Section s : top.tables("particle")) {
    ExplicitParticle p;
    p.material = material_index(c, s, "material");
    if (!(c.materials[p.material].density > 0)) s.fail("material", "particles need a material with density > 0");
    p.radius = s.num("radius", std::nullopt, 0, kInf, true, "m");
    p.x = s.vec3("position", std::nullopt);
    p.v = s.vec3("velocity", Vec3{});
    p.omega = s.vec3("omega", Vec3{});
    p.frozen = s.boolean("frozen", false);
    if (s.has("temperature")) {
      if (!c.thermal.enabled) s.fail("temperature", "a particle temperature needs a [thermal] table");
      p.temperature = s.num("temperature", std::nullopt, 0, kInf, true, "K");
    }
    if (s.has("attach_to")) {
      const std::string wn = s.str("attach_to", std::nullopt);
      for (size_t w = 0; w < c.walls.size(); ++w)
        if (c.walls[w].name == wn) p.attach_wall = int(w);
      if (p.attach_wall < 0) s.fail("attach_to", "unknown wall '" + wn + "'");
    }
    s.finish();
    c.particles.push_back(p);
  }
  c.particle_tables = c.particles.size();
  // [[particles]]: particles listed in CSV files.
  for (Section s : top.tables("particles")) {
    ExplicitParticle proto;
    proto.material = material_index(c, s, "material");
    if (!(c.materials[proto.material].density > 0)) s.fail("material", "particles need a material with density > 0");
    proto.frozen = s.boolean("frozen", false);
    const std::string path = beside_case(file, s.str("file", std::nullopt));
    s.finish();
    read_particle_file(path, s, proto, c.particles);
  }
  if (auto rs = top.table("ring_shear")) {
    std::vector<std::string> names;
    std::vector<double> densities;
    for (const auto& m : c.materials) { names.push_back(m.name); densities.push_back(m.density); }
    c.ring_shear = parse_ring_shear(*rs, names, densities);
  }
  if (c.inserts.empty() && c.particles.empty() && !c.ring_shear)
    top.fail("insert", "the case has no particles: add an [[insert]], [[particle]] or [[particles]]");

  // [[heat_source]]
  for (Section s : top.tables("heat_source")) {
    if (!c.thermal.enabled) s.fail("specific_power", "a heat source needs a [thermal] table");
    HeatSource hs;
    hs.name = s.str("name", s.path());
    hs.specific_power = read_schedule(s, "specific_power", -kInf, kInf, "W/kg");
    if (s.has("material")) hs.material = material_index(c, s, "material");
    if (auto r = s.table("region")) hs.region = read_region(*r, s.path());
    s.finish();
    c.thermal.sources.push_back(hs);
  }
  if (c.thermal.enabled) {
    auto need_heat_capacity = [&](int m, const std::string& where) {
      const Material& mat = c.materials[m];
      if (!(mat.heat_capacity > 0))
        throw InputError(file, material_line[m], "material." + mat.name + ".heat_capacity",
                         "particles of this material (" + where + ") need heat_capacity > 0 J/(kg K) when the case has [thermal]");
    };
    for (const auto& st : c.inserts) need_heat_capacity(st.spec.species, st.key);
    for (const auto& p : c.particles) need_heat_capacity(p.material, "[[particle]]");
    if (c.thermal.contact_radius == ThermalSettings::SpotRadius::HertzForce)
      for (int m = 0; m < nm; ++m) {
        const Material& mat = c.materials[m];
        if (mat.conductivity > 0 && !(mat.E > 0 || mat.E_conduction > 0))
          throw InputError(file, material_line[m], "material." + mat.name + ".conduction_youngs_modulus",
                           "thermal.contact_radius = \"hertz_force\" needs youngs_modulus or conduction_youngs_modulus > 0");
      }
  }

  // [output]
  if (auto s = top.table("output")) {
    c.output.folder = s->str("folder", "out");
    if (c.output.folder.empty()) s->fail("folder", "expected a non-empty folder name");
    c.output.frame_interval = s->num("frame_interval", 0.0, 0, kInf, false, "s");
    c.output.series_interval = s->num("series_interval", 0.0, 0, kInf, false, "s");
    c.output.progress_interval = s->num("progress_interval", 5.0, 0, kInf, true, "s");
    c.output.vtk = s->boolean("vtk", true);
    c.output.checkpoint_interval = s->num("checkpoint_interval", 600.0, 0, kInf, false, "s");
    c.output.contacts = s->boolean("contacts", false);
    c.cfg.record_contacts = c.output.contacts;  // the network shows each contact's force and radius
    c.output.probes = s->strings("probes", std::vector<std::string>{});
    static const std::vector<std::string> known = {"kinetic_energy", "rotational_energy", "contacts",
                                                   "max_overlap", "mean_velocity", "max_velocity",
                                                   "coordination", "particles", "rebuilds", "bed_height",
                                                   "max_contact_force", "mean_contact_force", "mean_temperature",
                                                   "min_temperature", "max_temperature"};
    for (const auto& p : c.output.probes) {
      if (std::find(known.begin(), known.end(), p) == known.end())
        s->fail("probes", "unknown probe '" + p + "'; known probes: " + Section::join(known));
      // The contact-force probes read each pair's force, which the force loop stores only
      // when asked to.
      if (p == "max_contact_force" || p == "mean_contact_force") c.cfg.record_contacts = true;
    }
    s->finish();
  }
  for (const auto& p : c.output.probes)
    if (p.find("temperature") != std::string::npos && !c.thermal.enabled)
      throw InputError(file, 0, "output.probes", "probe '" + p + "' needs a [thermal] table");
  top.finish({"case", "simulation", "domain", "material", "contact", "wall", "insert", "particle", "particles", "output", "ring_shear", "thermal",
              "heat_source"});

  // Derived defaults.
  double rmax = 0, rmin = kInf;
  for (const auto& st : c.inserts) { rmax = std::max(rmax, st.spec.size.max_radius()); rmin = std::min(rmin, st.spec.size.min_radius()); }
  for (const auto& p : c.particles) { rmax = std::max(rmax, p.radius); rmin = std::min(rmin, p.radius); }
  if (c.cfg.skin == 0) c.cfg.skin = 0.2 * rmax;  // 10% of the largest diameter
  return c;
}

Case finish_load(toml::table& root, const std::string& file, const std::vector<std::string>& overrides) {
  for (const auto& o : overrides) apply_override(root, o);
  return parse(root, file);
}

}  // namespace

uint64_t Case::steps() const { return uint64_t(std::llround(duration / cfg.dt)); }

Case load_case_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open case file");
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw InputError(path, int(e.source().begin.line), "", std::string("TOML syntax error: ") + std::string(e.description()));
  }
  return finish_load(root, path, overrides);
}

Case load_case_text(const std::string& text, const std::string& name, const std::vector<std::string>& overrides) {
  toml::table root;
  try {
    root = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    throw InputError(name, int(e.source().begin.line), "", std::string("TOML syntax error: ") + std::string(e.description()));
  }
  return finish_load(root, name, overrides);
}

std::unique_ptr<System> build_system(const Case& c, bool fill) {
  auto s = std::make_unique<System>();
  s->cfg = c.cfg;
  s->materials = c.materials;
  s->rng = Rng(c.seed);
  s->set_model(make_contact_model(c.model, c.rolling, c.file), c.pair_params);
  s->walls = c.walls;
  if (c.thermal.enabled) {
    s->thermal = std::make_shared<ThermalModel>(c.thermal, c.materials);
    s->particles.enable_thermal(c.cfg.initial_temperature);  // before the particles: their tables' temperatures
  }
  if (fill) {  // the particle arrays sized to what is known (fills to a solids fraction: trimmed below)
    size_t n = c.particles.size();
    for (const auto& st : c.inserts) n += st.pour ? 0 : st.spec.count;
    s->particles.reserve(n);
  }
  for (const auto& p : c.particles) {
    if (!fill) break;
    const size_t i = s->add_particle(p.material, p.radius, p.x, p.v, p.omega);
    if (p.temperature > 0) s->particles.temperature[i] = p.temperature;
    if (p.frozen) s->particles.flag[i] = kFrozen;
    if (p.attach_wall >= 0) s->particles.attach(i, p.attach_wall);
  }
  for (const auto& st : c.inserts) {
    if (st.pour) {
      PourSource ps;
      ps.spec = st.spec;
      ps.rate = st.rate;
      ps.t_start = st.start;
      ps.interval = st.interval;
      ps.next_time = st.start;
      s->pours.push_back(ps);
    } else if (fill) {
      try {
        s->insert(st.spec);
      } catch (const RunError& e) {
        // A fill that cannot fit is a problem of the case file: name the [[insert]].
        throw InputError(c.file, st.line, st.key, e.what());
      }
    }
  }
  s->particles.shrink_to_fit();  // a fill to a solids fraction grew them by doubling
  return s;
}

}  // namespace cohdem

namespace cohdem {
SizeDistribution read_size_distribution(Section s) { return read_size(std::move(s)); }
}  // namespace cohdem
