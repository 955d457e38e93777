#pragma once
// Parameters declared once (issue 18). Each parameter struct lists its parameters in one
// ParamSchema — key, field, constraint, unit, description — and everything else is derived from
// that list: reading a file section (absent keys keep the struct's default, unknown keys are
// errors), validation with messages built from the constraint and the full dotted key, and the
// dump of every value with its unit and constraint (`alight-params --dump`). The default of a
// parameter is the struct's member initialiser, so it too is written once.
//
//   const ParamSchema<OuterLoopParams>& OuterLoopParams::schema() {
//     static const auto s = [] {
//       ParamSchema<OuterLoopParams> s;
//       s.add("pose_stale_s", &P::pose_stale_s, Range::open_closed(0, 2), "s",
//             "pose older than this: level attitude, hover thrust");
//       s.add("pose_lost_s", &P::pose_lost_s, Range::open_closed(0, 5), "s", "...")
//           .check([](const P& p) { return p.pose_lost_s > p.pose_stale_s; },
//                  "must exceed pose_stale_s");
//       return s;
//     }();
//     return s;
//   }

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/params.hpp"

namespace alight {

/// A constraint on a number: an interval whose ends are open, closed or absent. Its text is both
/// the error message ("must be in (0, 2] s") and the dump's comment.
class Range {
 public:
  static Range any() { return Range(); }
  static Range gt(double lo) { return Range(lo, false, std::nullopt, false); }
  static Range ge(double lo) { return Range(lo, true, std::nullopt, false); }
  static Range lt(double hi) { return Range(std::nullopt, false, hi, false); }
  static Range le(double hi) { return Range(std::nullopt, false, hi, true); }
  static Range open(double lo, double hi) { return Range(lo, false, hi, false); }
  static Range closed(double lo, double hi) { return Range(lo, true, hi, true); }
  static Range open_closed(double lo, double hi) { return Range(lo, false, hi, true); }
  static Range closed_open(double lo, double hi) { return Range(lo, true, hi, false); }

  /// False for NaN and for infinities outside a bounded side.
  bool contains(double v) const;
  /// "in (0, 2] s", "> 0 s", ">= 1", or "" for any().
  std::string text(const std::string& unit) const;

 private:
  Range() = default;
  Range(std::optional<double> lo, bool lo_closed, std::optional<double> hi, bool hi_closed)
      : lo_(lo), hi_(hi), lo_closed_(lo_closed), hi_closed_(hi_closed) {}
  std::optional<double> lo_, hi_;
  bool lo_closed_ = false, hi_closed_ = false;
};

/// One parameter as the dump and the tests see it.
struct ParamInfo {
  std::string key;    ///< full dotted key below the schema's root, e.g. "star.max_size"
  std::string value;  ///< current value as YAML ("0.3", "[0, 0, 1]", "\"GREY\"")
  std::string unit;   ///< e.g. "s", "m/s", "" for none
  std::string rule;   ///< the constraint as text ("in (0, 2] s", "one of GREY, YUYV")
  std::string doc;    ///< what it means
  bool required = false;
};

namespace param_detail {
/// Numbers as the shortest text that reads back to the same value (YAML-compatible).
std::string number_text(double v);
std::string quote(const std::string& s);

inline std::string to_yaml(bool v) { return v ? "true" : "false"; }
inline std::string to_yaml(const std::string& v) { return quote(v); }
template <class T, std::enable_if_t<std::is_arithmetic_v<T>, int> = 0>
std::string to_yaml(T v) {
  if constexpr (std::is_floating_point_v<T>) return number_text(v);
  else return std::to_string(v);
}
template <class E, size_t N>
std::string to_yaml(const std::array<E, N>& a);
template <class E>
std::string to_yaml(const std::vector<E>& a);
template <int N>
std::string to_yaml(const Eigen::Matrix<double, N, 1>& v) {
  std::string out = "[";
  for (int i = 0; i < N; ++i) out += (i ? ", " : "") + number_text(v[i]);
  return out + "]";
}
template <class E, size_t N>
std::string to_yaml(const std::array<E, N>& a) {
  std::string out = "[";
  for (size_t i = 0; i < N; ++i) out += (i ? ", " : "") + to_yaml(a[i]);
  return out + "]";
}
template <class E>
std::string to_yaml(const std::vector<E>& a) {
  std::string out = "[";
  for (size_t i = 0; i < a.size(); ++i) out += (i ? ", " : "") + to_yaml(a[i]);
  return out + "]";
}

/// Every number inside a value is finite (values built in code bypass the loader's check).
template <class T>
bool all_finite(const T& v) {
  if constexpr (std::is_floating_point_v<T>) return std::isfinite(v);
  else if constexpr (std::is_arithmetic_v<T>) return true;
  else if constexpr (std::is_same_v<T, std::string>) return true;
  else if constexpr (std::is_base_of_v<Eigen::MatrixBase<T>, T>) return v.allFinite();
  else {
    for (const auto& e : v)
      if (!all_finite(e)) return false;
    return true;
  }
}

/// The value a located error shows: as written in the file when it is there, else the value.
std::string shown_value(const ParamNode& n, const std::string& key, const std::string& value);

/// Writes `# comment` lines and `key: value` at `indent` for one parameter.
void dump_line(std::ostream& out, int indent, const ParamInfo& info, const std::string& key);
void dump_section_head(std::ostream& out, int indent, const std::string& key,
                       const std::string& doc);
/// Writes `text` with "# " inserted after the indentation of each line.
void comment_out(std::ostream& out, const std::string& text, int indent);
}  // namespace param_detail

template <class P>
class ParamSchema {
 private:
  struct Entry;

 public:
  using Check = std::function<bool(const P&)>;

  /// Builder returned by add(): optional parts of a declaration.
  template <class T>
  class Param {
   public:
    /// The key must be in the file (no default applies).
    Param& required() {
      e_->required = true;
      return *this;
    }
    /// A further condition, typically on other fields of the struct; `problem` is the message
    /// ("must exceed pose_stale_s").
    Param& check(Check ok, std::string problem) {
      e_->checks.emplace_back(std::move(ok), std::move(problem));
      return *this;
    }
    /// For strings: the value must be one of `values` (the message lists them).
    Param& one_of(std::vector<std::string> values) {
      static_assert(std::is_same_v<T, std::string>, "one_of() is for string parameters");
      e_->rule = "one of " + join(values);
      const auto field = field_;
      e_->checks.emplace_back(
          [field, values](const P& p) {
            for (const auto& v : values)
              if (p.*field == v) return true;
            return false;
          },
          "must be " + join_or(values));
      return *this;
    }

   private:
    friend class ParamSchema;
    Param(Entry* e, T P::*field) : e_(e), field_(field) {}
    static std::string join(const std::vector<std::string>& v) {
      std::string s;
      for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
      return s;
    }
    static std::string join_or(const std::vector<std::string>& v) {
      std::string s;
      for (size_t i = 0; i < v.size(); ++i)
        s += (i == 0 ? "" : (i + 1 == v.size() ? " or " : ", ")) + v[i];
      return s;
    }
    Entry* e_;
    T P::*field_;
  };

  /// Declares a parameter. `range` constrains numbers (and each number of a fixed-size list or
  /// vector); pass Range::any() for none. Non-finite numbers are always refused.
  template <class T>
  Param<T>& add(std::string key, T P::*field, Range range, std::string unit, std::string doc) {
    auto e = std::make_unique<Entry>();
    e->key = std::move(key);
    e->unit = std::move(unit);
    e->doc = std::move(doc);
    e->rule = range.text(e->unit);
    e->read = [field](const ParamNode& n, const std::string& k, P& p) { n.read(k, p.*field); };
    e->present = [](const ParamNode& n, const std::string& k) { return n.has(k); };
    e->value = [field](const P& p) { return param_detail::to_yaml(p.*field); };
    e->valid = [field, range, u = e->unit](const P& p) -> std::optional<std::string> {
      if (!param_detail::all_finite(p.*field)) return std::string("must be finite");
      if (!in_range(p.*field, range)) return "must be " + range.text(u);
      return std::nullopt;
    };
    Entry* raw = e.get();
    entries_.push_back(std::move(e));
    params_.push_back(std::unique_ptr<void, void (*)(void*)>(
        new Param<T>(raw, field), [](void* q) { delete static_cast<Param<T>*>(q); }));
    return *static_cast<Param<T>*>(params_.back().get());
  }

  /// A sub-mapping `key:` read into the member `sub` with its own schema (absent: defaults).
  template <class S>
  void section(std::string key, S P::*sub, const ParamSchema<S>& schema, std::string doc = "",
               bool P::*present = nullptr) {
    auto e = std::make_unique<Entry>();
    e->key = std::move(key);
    e->doc = std::move(doc);
    e->is_section = true;
    const ParamSchema<S>* s = &schema;
    e->read = [sub, s, present](const ParamNode& n, const std::string& k, P& p) {
      const auto child = n.optional_child(k);
      if (present) p.*present = child.has_value();
      if (child) s->read(*child, p.*sub);
    };
    e->validate_section = [sub, s](const P& p, const std::string& prefix) {
      s->validate(p.*sub, prefix);
    };
    e->info = [sub, s](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      s->collect(p.*sub, prefix, out);
    };
    e->dump = [sub, s](std::ostream& out, const P& p, int indent) { s->dump(out, p.*sub, indent); };
    entries_.push_back(std::move(e));
  }

  /// An optional sub-mapping: the member holds a value exactly when the file has the section.
  template <class S>
  void optional_section(std::string key, std::optional<S> P::*sub, const ParamSchema<S>& schema,
                        std::string doc = "") {
    auto e = std::make_unique<Entry>();
    e->key = std::move(key);
    e->doc = std::move(doc);
    e->is_section = true;
    const ParamSchema<S>* s = &schema;
    e->read = [sub, s](const ParamNode& n, const std::string& k, P& p) {
      if (const auto child = n.optional_child(k)) {
        S v;
        s->read(*child, v);
        p.*sub = v;
      }
    };
    e->validate_section = [sub, s](const P& p, const std::string& prefix) {
      if (p.*sub) s->validate(*(p.*sub), prefix);
    };
    e->info = [sub, s](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      s->collect(p.*sub ? *(p.*sub) : S{}, prefix, out);
    };
    e->dump = [sub, s](std::ostream& out, const P& p, int indent) {
      s->dump(out, p.*sub ? *(p.*sub) : S{}, indent);
    };
    e->present_in = [sub](const P& p) { return (p.*sub).has_value(); };
    e->optional_section = true;
    entries_.push_back(std::move(e));
  }

  /// The parameters of member `sub` at this same level of the file (a struct that groups some
  /// of a section's keys in code but not in the file).
  template <class S>
  void merge(S P::*sub, const ParamSchema<S>& schema) {
    auto e = std::make_unique<Entry>();
    e->is_merge = true;
    const ParamSchema<S>* s = &schema;
    e->read = [sub, s](const ParamNode& n, const std::string&, P& p) {
      s->read_keys(n, p.*sub);
    };
    e->validate_section = [sub, s](const P& p, const std::string& prefix) {
      s->validate(p.*sub, prefix);
    };
    e->info = [sub, s](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      s->collect(p.*sub, prefix, out);
    };
    e->dump = [sub, s](std::ostream& out, const P& p, int indent) {
      s->dump_entries(out, p.*sub, indent);
    };
    entries_.push_back(std::move(e));
  }

  /// A key read by hand (lists of pairs, values that load a file): `read` fills the struct from
  /// the section, `value` gives the dump's YAML. Validation belongs in check().
  void custom(std::string key, std::function<void(const ParamNode&, P&)> read,
              std::function<std::string(const P&)> value, std::string unit, std::string doc) {
    auto e = std::make_unique<Entry>();
    e->key = std::move(key);
    e->unit = std::move(unit);
    e->doc = std::move(doc);
    e->read = [read](const ParamNode& n, const std::string&, P& p) { read(n, p); };
    e->present = [](const ParamNode& n, const std::string& k) { return n.has(k); };
    e->value = std::move(value);
    e->valid = [](const P&) -> std::optional<std::string> { return std::nullopt; };
    entries_.push_back(std::move(e));
  }

  /// A condition across several fields, reported on `key`.
  void check(std::string key, Check ok, std::string problem) {
    relations_.push_back({std::move(key), std::move(ok), std::move(problem)});
  }

  /// Reads this schema's keys from `n` into `p` (absent keys keep p's values), validates them and
  /// rejects keys of `n` nobody declared (`ignored`: keys that belong to other components).
  void read(const ParamNode& n, P& p, const std::vector<std::string>& ignored = {}) const {
    read_keys(n, p);
    try {
      validate(p);
    } catch (const ParamError& e) {
      // Shows the value as written when the key is in this file.
      const std::string rel = e.key();
      const auto dot = rel.find('.');
      const bool local = dot == std::string::npos;
      const std::string value =
          local && n.has(rel) ? param_detail::shown_value(n, rel, e.value()) : e.value();
      throw ParamError(n.file(), n.key_path(rel), value, e.problem());
    }
    n.finish(ignored);
  }

  /// Throws ParamError (no file) naming `prefix` + the key, the value and the problem for the
  /// first parameter of `p` that breaks its declaration.
  void validate(const P& p, const std::string& prefix = "") const {
    for (const auto& e : entries_) {
      if (e->is_section || e->is_merge) {
        e->validate_section(p, e->is_merge ? prefix : prefix + e->key + ".");
        continue;
      }
      if (auto problem = e->valid(p)) throw ParamError("", prefix + e->key, e->value(p), *problem);
      for (const auto& [ok, problem] : e->checks)
        if (!ok(p)) throw ParamError("", prefix + e->key, e->value(p), problem);
    }
    for (const auto& r : relations_)
      if (!r.ok(p)) throw ParamError("", prefix + r.key, value_of(p, r.key), r.problem);
  }

  /// Every parameter with its current value in `p`, in declaration order.
  std::vector<ParamInfo> params(const P& p) const {
    std::vector<ParamInfo> out;
    collect(p, "", out);
    return out;
  }

  /// `p` as YAML at `indent` spaces, each key preceded by a comment with its unit, constraint
  /// and meaning; reads back to the same values.
  void dump(std::ostream& out, const P& p, int indent) const { dump_entries(out, p, indent); }

 private:
  template <class S>
  friend class ParamSchema;

  struct Entry {
    std::string key, unit, doc, rule;
    bool required = false, is_section = false, is_merge = false, optional_section = false;
    std::function<void(const ParamNode&, const std::string&, P&)> read;
    std::function<bool(const ParamNode&, const std::string&)> present;
    std::function<std::string(const P&)> value;
    std::function<std::optional<std::string>(const P&)> valid;
    std::vector<std::pair<Check, std::string>> checks;
    std::function<void(const P&, const std::string&)> validate_section;
    std::function<void(const P&, const std::string&, std::vector<ParamInfo>&)> info;
    std::function<void(std::ostream&, const P&, int)> dump;
    std::function<bool(const P&)> present_in;
  };
  struct Relation {
    std::string key;
    Check ok;
    std::string problem;
  };

  template <class T>
  static bool in_range(const T& v, const Range& r) {
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      return r.contains(static_cast<double>(v));
    } else if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, std::string>) {
      return true;
    } else {
      for (const auto& e : v)
        if (!in_range(e, r)) return false;
      return true;
    }
  }

  void read_keys(const ParamNode& n, P& p) const {
    for (const auto& e : entries_) {
      if (e->required && !e->is_section && !n.has(e->key))
        throw n.error(e->key, "<missing>", "required key is missing");
      e->read(n, e->key, p);
    }
  }

  std::string value_of(const P& p, const std::string& key) const {
    for (const auto& e : entries_)
      if (!e->is_section && !e->is_merge && e->key == key) return e->value(p);
    return "";
  }

  void collect(const P& p, const std::string& prefix, std::vector<ParamInfo>& out) const {
    for (const auto& e : entries_) {
      if (e->is_section || e->is_merge) {
        e->info(p, e->is_merge ? prefix : prefix + e->key + ".", out);
        continue;
      }
      out.push_back({prefix + e->key, e->value(p), e->unit, e->rule, e->doc, e->required});
    }
  }

  void dump_entries(std::ostream& out, const P& p, int indent) const {
    for (const auto& e : entries_) {
      if (e->is_merge) {
        e->dump(out, p, indent);
      } else if (e->is_section) {
        std::ostringstream text;
        param_detail::dump_section_head(text, indent, e->key,
                                        e->doc + (e->optional_section ? " (optional section)" : ""));
        e->dump(text, p, indent + 2);
        // An absent optional section is shown as comments: the dump reads back to the same.
        if (e->optional_section && !e->present_in(p))
          param_detail::comment_out(out, text.str(), indent);
        else
          out << text.str();
      } else {
        param_detail::dump_line(out, indent,
                                {e->key, e->value(p), e->unit, e->rule, e->doc, e->required},
                                e->key);
      }
    }
  }

  std::vector<std::unique_ptr<Entry>> entries_;
  std::vector<std::unique_ptr<void, void (*)(void*)>> params_;
  std::vector<Relation> relations_;
};

}  // namespace alight
