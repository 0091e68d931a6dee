#include "io/checkpoint.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace cohdem {

namespace {

constexpr char kMagic[8] = {'C', 'O', 'H', 'D', 'E', 'M', 'C', 'K'};
// 2: neighbor-list reference state and application state; 3: the trigger's drift origin and
// carried bounds (NeighborList::recheck).
constexpr uint32_t kVersion = 3;

// The checkpoint is written straight into the file (AtomicWriter's stream) and read straight
// from it, array by array: no copy of the whole state is held in memory on either side. (A
// buffer of the whole file, as before, was the largest transient of a run: at 10^5
// particles 39 MB, a third of the process's peak.)
class Out {
 public:
  explicit Out(std::ostream& os) : os_(os) {}
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    os_.write(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void vec(const std::vector<T>& v) {  // T: plain data (std::pair of integers included)
    pod(uint64_t(v.size()));
    if (!v.empty()) os_.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    os_.write(s.data(), std::streamsize(s.size()));
  }
  void bytes(const std::byte* p, uint64_t n) { os_.write(reinterpret_cast<const char*>(p), std::streamsize(n)); }

 private:
  std::ostream& os_;
};

class In {
 public:
  /// Reads `file`, whose size is `size` bytes, from `is`.
  In(std::istream& is, uint64_t size, std::string file) : is_(is), size_(size), file_(std::move(file)) {}
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    need(sizeof v);
    read(&v, sizeof v);
    return v;
  }
  template <class T>
  void vec(std::vector<T>& v) {
    const uint64_t n = pod<uint64_t>();
    if (n > (size_ - p_) / sizeof(T)) truncated();  // before the allocation: n may be garbage
    v.resize(n);
    if (n) read(v.data(), n * sizeof(T));
  }
  std::string str() {
    const uint64_t n = pod<uint64_t>();
    need(n);
    std::string s(n, '\0');
    if (n) read(s.data(), n);
    return s;
  }
  void need(uint64_t n) const {
    if (n > size_ - p_) truncated();
  }

 private:
  void read(void* dst, uint64_t n) {
    if (!is_.read(static_cast<char*>(dst), std::streamsize(n))) truncated();
    p_ += n;
  }
  [[noreturn]] void truncated() const { throw InputError(file_, 0, "", "checkpoint file is truncated"); }
  std::istream& is_;
  uint64_t size_, p_ = 0;
  std::string file_;
};

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const System& s, const std::string& app_state) {
  if (s.mid_step()) throw std::logic_error("write_checkpoint in the middle of a step (step_once(true))");
  AtomicWriter file(path, Sync::durable);
  Out o(file.stream());
  for (char c : kMagic) o.pod(c);
  o.pod(kVersion);
  o.str(s.model->name());
  o.pod(uint64_t(s.model->state_size()));
  o.pod(s.time);
  o.pod(s.step);
  o.pod(s.next_id);
  o.pod(s.nl.stats.builds);
  o.str(s.rng.state());
  const ParticleStore& P = s.particles;
  o.vec(P.id); o.vec(P.species); o.vec(P.flag); o.vec(P.body);
  o.vec(P.radius); o.vec(P.radius0); o.vec(P.mass); o.vec(P.inertia);
  o.vec(P.x); o.vec(P.v); o.vec(P.omega); o.vec(P.force); o.vec(P.torque);
  o.vec(P.temperature); o.vec(P.heat_flow);
  o.pod(uint64_t(s.walls.size()));
  for (const Wall& w : s.walls) {
    o.pod(w.point); o.pod(w.center); o.pod(w.vn); o.pod(w.travel); o.pod(w.force); o.pod(w.torque);
    o.pod(w.velocity); o.pod(w.omega); o.pod(w.target_force);
  }
  o.pod(uint64_t(s.pours.size()));
  for (const PourSource& p : s.pours) { o.pod(p.inserted); o.pod(p.next_time); }
  // The live contacts, in SavedContacts' layout (pair keys, pair records, wall keys, wall
  // records, each array after its length), written from the lists in three passes.
  uint64_t npair = 0, nwall = 0;
  s.visit_live_contacts([&](uint64_t, uint64_t, const std::byte*) { ++npair; },
                        [&](uint64_t, uint64_t, const std::byte*) { ++nwall; });
  const uint64_t st = s.model->state_size();
  auto keys = [&](uint64_t a, uint64_t b, const std::byte*) { o.pod(a); o.pod(b); };
  auto none = [](uint64_t, uint64_t, const std::byte*) {};
  o.pod(npair);
  s.visit_live_contacts(keys, none);
  o.pod(npair * st);
  s.visit_live_contacts([&](uint64_t, uint64_t, const std::byte* r) { o.bytes(r, st); }, none);
  o.pod(nwall);
  s.visit_live_contacts(none, keys);
  o.pod(nwall * st);
  s.visit_live_contacts(none, [&](uint64_t, uint64_t, const std::byte* r) { o.bytes(r, st); });
  const NeighborList::Reference& ref = s.nl.reference();
  o.vec(ref.x); o.vec(ref.r); o.vec(ref.wall);
  o.vec(ref.from); o.pod(ref.carried_pair); o.vec(ref.carried_wall);
  o.pod(s.nl.stats.checks); o.pod(s.nl.stats.deferred);
  o.str(app_state);
  file.commit();
}

std::string read_checkpoint(const std::filesystem::path& path, System& s) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string(), 0, "", "cannot open checkpoint file");
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path.string(), 0, "", "cannot read checkpoint file: " + ec.message());
  In in(f, size, path.string());
  for (char c : kMagic)
    if (in.pod<char>() != c) throw InputError(path.string(), 0, "", "not a cohdem checkpoint");
  const uint32_t version = in.pod<uint32_t>();
  if (version < 1 || version > kVersion) throw InputError(path.string(), 0, "", "unsupported checkpoint version");
  const std::string model = in.str();
  const uint64_t stride = in.pod<uint64_t>();
  if (model != s.model->name() || stride != s.model->state_size())
    throw InputError(path.string(), 0, "contact.model",
                     "checkpoint was written with contact model '" + model + "', the case uses '" + s.model->name() + "'");
  s.time = in.pod<double>();
  s.step = in.pod<uint64_t>();
  s.next_id = in.pod<uint64_t>();
  const uint64_t builds = in.pod<uint64_t>();
  s.rng.set_state(in.str());
  ParticleStore& P = s.particles;
  in.vec(P.id); in.vec(P.species); in.vec(P.flag); in.vec(P.body);
  in.vec(P.radius); in.vec(P.radius0); in.vec(P.mass); in.vec(P.inertia);
  in.vec(P.x); in.vec(P.v); in.vec(P.omega); in.vec(P.force); in.vec(P.torque);
  in.vec(P.temperature); in.vec(P.heat_flow);
  const size_t n = P.id.size();
  auto bad = [&](const char* what) {
    throw InputError(path.string(), 0, "", std::string("checkpoint's ") + what + " do not match its particles");
  };
  if (P.species.size() != n || P.flag.size() != n || P.radius.size() != n || P.mass.size() != n ||
      P.inertia.size() != n || P.x.size() != n || P.v.size() != n || P.omega.size() != n || P.force.size() != n ||
      P.torque.size() != n)
    bad("particle arrays");
  // Every particle is a solid sphere (sphere_inertia), which the contact lanes rely on.
  for (size_t i = 0; i < n; ++i)
    if (P.inertia[i] != sphere_inertia(P.mass[i], P.radius[i])) bad("moments of inertia (2/5 m r^2)");
  // The thermal fields: written by runs that keep them (ParticleStore::enable_thermal),
  // empty otherwise. A thermal case resuming a mechanical run's checkpoint starts every
  // particle at its initial temperature, with its current radius as the reference; a
  // mechanical case drops a thermal run's.
  for (const std::vector<double>* a : {&P.radius0, &P.temperature, &P.heat_flow})
    if (!a->empty() && a->size() != n) bad("thermal fields");
  if (s.thermal)
    P.enable_thermal(s.cfg.initial_temperature);
  else
    P.disable_thermal();
  if (in.pod<uint64_t>() != s.walls.size())
    throw InputError(path.string(), 0, "wall", "checkpoint has a different number of walls than the case");
  for (Wall& w : s.walls) {
    w.point = in.pod<Vec3>(); w.center = in.pod<Vec3>(); w.vn = in.pod<double>(); w.travel = in.pod<double>();
    w.force = in.pod<Vec3>(); w.torque = in.pod<Vec3>(); w.velocity = in.pod<Vec3>(); w.omega = in.pod<Vec3>();
    w.target_force = in.pod<double>();
  }
  // The wall indices: written by runs with attached particles (ParticleStore::attach), empty
  // otherwise (checkpoints before that change hold -1 for every unattached particle, dropped
  // here when none is attached). Each attached particle names one of the case's walls.
  if ((!P.body.empty() && P.body.size() != n) || P.first_bad_attachment(s.walls.size()) < n) bad("wall attachments");
  if (std::find(P.flag.begin(), P.flag.end(), uint8_t(kAttached)) == P.flag.end()) std::vector<int32_t>().swap(P.body);
  if (in.pod<uint64_t>() != s.pours.size())
    throw InputError(path.string(), 0, "insert", "checkpoint has a different number of pour sources than the case");
  for (PourSource& p : s.pours) { p.inserted = in.pod<uint64_t>(); p.next_time = in.pod<double>(); }
  System::SavedContacts c;
  in.vec(c.pair_keys); in.vec(c.pair_data); in.vec(c.wall_keys); in.vec(c.wall_data);
  s.restore_contacts(std::move(c));
  std::string app_state;
  uint64_t checks = 0, deferred = 0;  // the local checks' counts (version 3 on)
  if (version >= 2) {  // version 1 was written at a rebuild step: the current state is the reference
    NeighborList::Reference ref;
    in.vec(ref.x); in.vec(ref.r); in.vec(ref.wall);
    if (version >= 3) {  // before: the drift was always from the build's positions
      in.vec(ref.from);
      ref.carried_pair = in.pod<double>();
      in.vec(ref.carried_wall);
      checks = in.pod<uint64_t>();
      deferred = in.pod<uint64_t>();
      bool nan = false;
      for (const double c : ref.carried_wall) nan = nan || c != c;
      if ((!ref.from.empty() && ref.from.size() != n) || !(ref.carried_pair >= 0) || nan ||
          (!ref.carried_wall.empty() && ref.carried_wall.size() != s.walls.size()))
        throw InputError(path.string(), 0, "", "checkpoint's neighbor-list drift origin does not match its particles");
    }
    app_state = in.str();
    // ref.r is empty where the radii could not change since the lists were built.
    if (ref.x.size() != n || (!ref.r.empty() && ref.r.size() != n) || ref.wall.size() != s.walls.size())
      throw InputError(path.string(), 0, "", "checkpoint's neighbor-list state does not match its particles");
    s.resume_prepare(&ref);
  } else {
    s.resume_prepare();
  }
  s.nl.stats.builds = builds;  // the restart's own build does not count (re-sort schedule)
  s.nl.stats.checks = checks;
  s.nl.stats.deferred = deferred;
  return app_state;
}

}  // namespace cohdem
