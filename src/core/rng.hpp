// Reproducible random numbers: the same seed gives the same stream on every platform
// (std:: distributions are implementation-defined, so we draw from the raw engine).
#pragma once
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>

namespace cohdem {

class Rng {
 public:
  explicit Rng(uint64_t seed = 1) : eng_(seed) {}
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(eng_() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  /// Standard normal (Box-Muller, second value cached).
  double normal() {
    if (has_spare_) { has_spare_ = false; return spare_; }
    double u1;
    do { u1 = uniform(); } while (u1 <= 0.0);
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  uint64_t next() { return eng_(); }
  /// Full generator state as text (checkpoints).
  std::string state() const {
    std::ostringstream s;
    s << eng_ << ' ' << has_spare_ << ' ' << std::hexfloat << spare_;
    return s.str();
  }
  void set_state(const std::string& text) {
    std::istringstream s(text);
    s >> eng_ >> has_spare_;
    std::string sp;
    s >> sp;
    spare_ = std::strtod(sp.c_str(), nullptr);
  }

 private:
  std::mt19937_64 eng_;
  bool has_spare_ = false;
  double spare_ = 0;
};

}  // namespace cohdem
