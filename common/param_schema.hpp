#pragma once
// Parameters declared once. Each parameter struct lists its parameters in one
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

  const std::optional<double>& lo() const { return lo_; }
  const std::optional<double>& hi() const { return hi_; }
  bool lo_closed() const { return lo_closed_; }
  bool hi_closed() const { return hi_closed_; }

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
  Range range = Range::any();  ///< the constraint on each number of the value
  bool integer = false;        ///< an integer parameter (its range's ends are whole numbers)
};

namespace param_detail {
/// Numbers as the shortest text that reads back to the same value (YAML-compatible).
std::string number_text(double v);
std::string quote(const std::string& s);

inline std::string to_yaml(bool v) { return v ? "true" : "false"; }
inline std::string to_yaml(const std::string& v) { return quote(v); }
template <class T, std::enable_if_t<std::is_arithmetic_v<T>, int> = 0>
std::string to_yaml(T v) {
  if constexpr (std::is_floating_point_v<T>)
    return number_text(v);
  else
    return std::to_string(v);
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

/// A value as an error message shows it: as the dump writes it, strings without quotes.
template <class T>
std::string error_text(const T& v) {
  if constexpr (std::is_same_v<T, std::string>)
    return v;
  else
    return to_yaml(v);
}

/// Every number inside a value is finite (values built in code bypass the loader's check).
template <class T>
bool all_finite(const T& v) {
  if constexpr (std::is_floating_point_v<T>)
    return std::isfinite(v);
  else if constexpr (std::is_arithmetic_v<T>)
    return true;
  else if constexpr (std::is_same_v<T, std::string>)
    return true;
  else if constexpr (std::is_base_of_v<Eigen::MatrixBase<T>, T>)
    return v.allFinite();
  else {
    for (const auto& e : v)
      if (!all_finite(e)) return false;
    return true;
  }
}

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
    /// ("must exceed pose_stale_s"). Checked after every field is within its range.
    Param& check(Check ok, std::string problem) {
      e_->checks.push_back([ok = std::move(ok), problem = std::move(problem)](
                               const P& p) -> std::optional<std::string> {
        if (ok(p)) return std::nullopt;
        return problem;
      });
      return *this;
    }
    /// A condition whose message depends on the value: `problem` returns "" when it holds.
    Param& check_with(std::function<std::string(const P&)> problem) {
      e_->checks.push_back(
          [problem = std::move(problem)](const P& p) -> std::optional<std::string> {
            std::string why = problem(p);
            if (why.empty()) return std::nullopt;
            return why;
          });
      return *this;
    }
    /// For strings: the value must be one of `values` (the message lists them).
    Param& one_of(std::vector<std::string> values) {
      static_assert(std::is_same_v<T, std::string>, "one_of() is for string parameters");
      e_->rule = "one of " + join(values);
      const auto field = field_;
      return check(
          [field, values](const P& p) {
            for (const auto& v : values)
              if (p.*field == v) return true;
            return false;
          },
          "must be " + join_or(values));
    }
    /// For strings: a file path, relative to the folder of the file it is read from. Reading
    /// resolves it (the default too, when not empty), so the struct holds a usable path.
    Param& path() {
      static_assert(std::is_same_v<T, std::string>, "path() is for string parameters");
      const auto field = field_;
      e_->read = [field](const ParamNode& n, const std::string& k, P& p) {
        n.read(k, p.*field);
        if (!(p.*field).empty()) p.*field = resolve_relative(n.file(), p.*field);
      };
      e_->rule = "a path relative to this file's folder";
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
    e->range = range;
    e->integer = std::is_integral_v<T> && !std::is_same_v<T, bool>;
    e->read = [field](const ParamNode& n, const std::string& k, P& p) { n.read(k, p.*field); };
    e->value = [field](const P& p) { return param_detail::to_yaml(p.*field); };
    e->shown = [field](const P& p) { return param_detail::error_text(p.*field); };
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
  /// With `present`, the flag records whether the file has the section, and the section is
  /// validated (and dumped other than as a comment) only when it does.
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
    e->validate_section = [sub, s, present](const P& p, const std::string& prefix) {
      if (!present || p.*present) s->validate(p.*sub, prefix);
    };
    e->info = [sub, s](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      s->collect(p.*sub, prefix, out);
    };
    e->find = [sub, s](const P& p, const std::string& key) { return s->find_shown(p.*sub, key); };
    e->dump = [sub, s](std::ostream& out, const P& p, int indent) { s->dump(out, p.*sub, indent); };
    if (present) {
      e->optional_section = true;
      e->present_in = [present](const P& p) { return p.*present; };
    }
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
    e->find = [sub, s](const P& p, const std::string& key) {
      return s->find_shown(p.*sub ? *(p.*sub) : S{}, key);
    };
    e->dump = [sub, s](std::ostream& out, const P& p, int indent) {
      s->dump(out, p.*sub ? *(p.*sub) : S{}, indent);
    };
    e->present_in = [sub](const P& p) { return (p.*sub).has_value(); };
    e->optional_section = true;
    entries_.push_back(std::move(e));
  }

  /// A sub-mapping `key:` whose parameters are fields of P itself (a struct that is flat in code
  /// and nested in the file); `build` declares them on the group's schema. `present` as for
  /// section().
  void group(std::string key, std::string doc, const std::function<void(ParamSchema&)>& build,
             bool P::*present = nullptr) {
    auto g = std::make_shared<ParamSchema>();
    build(*g);
    auto e = std::make_unique<Entry>();
    e->key = std::move(key);
    e->doc = std::move(doc);
    e->is_section = true;
    // Validated with the rest of P (its checks may involve fields outside the group).
    e->read = [g, present](const ParamNode& n, const std::string& k, P& p) {
      const auto child = n.optional_child(k);
      if (present) p.*present = child.has_value();
      if (child) {
        g->read_keys(*child, p);
        child->finish();
      }
    };
    e->validate_section = [g, present](const P& p, const std::string& prefix) {
      if (!present || p.*present) g->validate(p, prefix);
    };
    e->info = [g](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      g->collect(p, prefix, out);
    };
    e->find = [g](const P& p, const std::string& key) { return g->find_shown(p, key); };
    e->dump = [g](std::ostream& out, const P& p, int indent) { g->dump_entries(out, p, indent); };
    if (present) {
      e->optional_section = true;
      e->present_in = [present](const P& p) { return p.*present; };
    }
    entries_.push_back(std::move(e));
  }

  /// The parameters of member `sub` at this same level of the file (a struct that groups some
  /// of a section's keys in code but not in the file).
  template <class S>
  void merge(S P::*sub, const ParamSchema<S>& schema) {
    auto e = std::make_unique<Entry>();
    e->is_merge = true;
    const ParamSchema<S>* s = &schema;
    e->read = [sub, s](const ParamNode& n, const std::string&, P& p) { s->read_keys(n, p.*sub); };
    e->validate_section = [sub, s](const P& p, const std::string& prefix) {
      s->validate(p.*sub, prefix);
    };
    e->info = [sub, s](const P& p, const std::string& prefix, std::vector<ParamInfo>& out) {
      s->collect(p.*sub, prefix, out);
    };
    e->find = [sub, s](const P& p, const std::string& key) { return s->find_shown(p.*sub, key); };
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
    e->value = value;
    e->shown = std::move(value);
    e->valid = [](const P&) -> std::optional<std::string> { return std::nullopt; };
    entries_.push_back(std::move(e));
  }

  /// A condition across several fields, reported on `key` (dotted for a key in a section).
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
      throw ParamError(n.file(), n.key_path(e.key()), e.value(), e.problem());
    }
    n.finish(ignored);
  }

  /// Throws ParamError (no file) naming `prefix` + the key, the value and the problem for the
  /// first parameter of `p` that breaks its declaration: first every value against its range
  /// (so a value out of range is reported at its own key, not at one whose check involves it),
  /// then the checks, then the relations.
  void validate(const P& p, const std::string& prefix = "") const {
    for (const auto& e : entries_) {
      if (e->is_section || e->is_merge) {
        e->validate_section(p, e->is_merge ? prefix : prefix + e->key + ".");
        continue;
      }
      if (auto problem = e->valid(p)) throw ParamError("", prefix + e->key, e->shown(p), *problem);
    }
    for (const auto& e : entries_)
      for (const auto& check : e->checks)
        if (auto problem = check(p)) throw ParamError("", prefix + e->key, e->shown(p), *problem);
    for (const auto& r : relations_)
      if (!r.ok(p))
        throw ParamError("", prefix + r.key, find_shown(p, r.key).value_or(""), r.problem);
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
    Range range = Range::any();
    bool integer = false;
    bool required = false, is_section = false, is_merge = false, optional_section = false;
    std::function<void(const ParamNode&, const std::string&, P&)> read;
    std::function<std::string(const P&)> value;  // as YAML, for the dump
    std::function<std::string(const P&)> shown;  // as an error message shows it
    std::function<std::optional<std::string>(const P&)> valid;
    std::vector<std::function<std::optional<std::string>(const P&)>> checks;
    std::function<void(const P&, const std::string&)> validate_section;
    std::function<void(const P&, const std::string&, std::vector<ParamInfo>&)> info;
    std::function<std::optional<std::string>(const P&, const std::string&)> find;
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

  /// The value of the parameter at dotted `key` as an error shows it.
  std::optional<std::string> find_shown(const P& p, const std::string& key) const {
    for (const auto& e : entries_) {
      if (e->is_merge) {
        if (auto v = e->find(p, key)) return v;
      } else if (e->is_section) {
        if (key.compare(0, e->key.size() + 1, e->key + ".") == 0)
          if (auto v = e->find(p, key.substr(e->key.size() + 1))) return v;
      } else if (e->key == key) {
        return e->shown(p);
      }
    }
    return std::nullopt;
  }

  void collect(const P& p, const std::string& prefix, std::vector<ParamInfo>& out) const {
    for (const auto& e : entries_) {
      if (e->is_section || e->is_merge) {
        e->info(p, e->is_merge ? prefix : prefix + e->key + ".", out);
        continue;
      }
      out.push_back(info_of(*e, p, prefix + e->key));
    }
  }

  static ParamInfo info_of(const Entry& e, const P& p, const std::string& key) {
    ParamInfo i;
    i.key = key;
    i.value = e.value(p);
    i.unit = e.unit;
    i.rule = e.rule;
    i.doc = e.doc;
    i.required = e.required;
    i.range = e.range;
    i.integer = e.integer;
    return i;
  }

  void dump_entries(std::ostream& out, const P& p, int indent) const {
    for (const auto& e : entries_) {
      if (e->is_merge) {
        e->dump(out, p, indent);
      } else if (e->is_section) {
        std::ostringstream text;
        const std::string doc = !e->optional_section ? e->doc
                                : e->doc.empty()     ? std::string("optional section")
                                                     : e->doc + " (optional section)";
        param_detail::dump_section_head(text, indent, e->key, doc);
        e->dump(text, p, indent + 2);
        // An absent optional section is shown as comments: the dump reads back to the same.
        if (e->optional_section && !e->present_in(p))
          param_detail::comment_out(out, text.str(), indent);
        else
          out << text.str();
      } else {
        param_detail::dump_line(out, indent, info_of(*e, p, e->key), e->key);
      }
    }
  }

  std::vector<std::unique_ptr<Entry>> entries_;
  std::vector<std::unique_ptr<void, void (*)(void*)>> params_;
  std::vector<Relation> relations_;
};

}  // namespace alight
