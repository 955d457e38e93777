#include "common/param_schema.hpp"

#include <algorithm>
#include <charconv>

namespace alight {

bool Range::contains(double v) const {
  if (std::isnan(v)) return false;
  if (lo_ && (lo_closed_ ? v < *lo_ : v <= *lo_)) return false;
  if (hi_ && (hi_closed_ ? v > *hi_ : v >= *hi_)) return false;
  return true;
}

std::string Range::text(const std::string& unit) const {
  using param_detail::number_text;
  std::string t;
  if (lo_ && hi_)
    t = std::string("in ") + (lo_closed_ ? "[" : "(") + number_text(*lo_) + ", " +
        number_text(*hi_) + (hi_closed_ ? "]" : ")");
  else if (lo_)
    t = std::string(lo_closed_ ? ">= " : "> ") + number_text(*lo_);
  else if (hi_)
    t = std::string(hi_closed_ ? "<= " : "< ") + number_text(*hi_);
  else
    return "";
  return unit.empty() ? t : t + " " + unit;
}

namespace param_detail {

std::string number_text(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  // YAML reads "inf" and "nan" as strings; the loader refuses non-finite values anyway, but a
  // dump of a struct built in code must still say what it holds.
  if (s == "inf") return ".inf";
  if (s == "-inf") return "-.inf";
  if (s == "nan" || s == "-nan") return ".nan";
  return s;
}

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

namespace {
// `# text` at `pad`, wrapped at spaces to keep lines within 100 columns, also when an absent
// optional section (and one inside it) is commented out.
void write_comment(std::ostream& out, const std::string& pad, const std::string& text) {
  const size_t width = pad.size() < 56 ? 96 - pad.size() - 2 : 40;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.size();
    if (end - start > width) {
      end = text.rfind(' ', start + width);
      if (end == std::string::npos || end <= start) end = text.find(' ', start + width);
      if (end == std::string::npos) end = text.size();
    }
    out << pad << "# " << text.substr(start, end - start) << "\n";
    start = end + (end < text.size() ? 1 : 0);
  }
}
}  // namespace

void dump_line(std::ostream& out, int indent, const ParamInfo& info, const std::string& key) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  std::string comment = info.doc;
  // The rule names the unit when there is one ("in (0, 2] s").
  if (!info.rule.empty())
    comment += (comment.empty() ? "" : "; ") + info.rule;
  else if (!info.unit.empty())
    comment += " [" + info.unit + "]";
  if (info.required) comment += (comment.empty() ? "" : "; ") + std::string("required");
  if (!comment.empty()) write_comment(out, pad, comment);
  out << pad << key << ": " << info.value << "\n";
}

void dump_section_head(std::ostream& out, int indent, const std::string& key,
                       const std::string& doc) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  if (!doc.empty()) write_comment(out, pad, doc);
  out << pad << key << ":\n";
}

void comment_out(std::ostream& out, const std::string& text, int indent) {
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    const std::string line =
        text.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const size_t at = std::min(line.find_first_not_of(' '), static_cast<size_t>(indent));
    out << line.substr(0, at) << "# " << line.substr(at) << "\n";
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

}  // namespace param_detail
}  // namespace alight
