// A small XML well-formedness checker for the tests (no XML library in the build): every
// element closed in order, attributes quoted and unique, only the five named entities or
// character references, nothing after the root. Collects each element's attributes.
#pragma once
#include <cctype>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace stepnode::tools::testing {

struct XmlElement {
  std::string name;
  std::map<std::string, std::string> attributes;
};

class XmlCheck {
 public:
  // Throws std::runtime_error naming the offset and the problem.
  explicit XmlCheck(const std::string& text) : s_(text) {
    skip_space();
    if (s_.compare(i_, 5, "<?xml") == 0) {
      i_ = s_.find("?>", i_);
      if (i_ == std::string::npos) fail("unterminated XML declaration");
      i_ += 2;
    }
    skip_misc();
    if (i_ >= s_.size() || s_[i_] != '<') fail("no root element");
    element();
    skip_misc();
    if (i_ != s_.size()) fail("content after the root element");
  }
  const std::vector<XmlElement>& elements() const { return elements_; }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error("XML at offset " + std::to_string(i_) + ": " + why);
  }
  void skip_space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  void skip_misc() {
    for (;;) {
      skip_space();
      if (s_.compare(i_, 4, "<!--") != 0) return;
      i_ = s_.find("-->", i_);
      if (i_ == std::string::npos) fail("unterminated comment");
      i_ += 3;
    }
  }
  std::string name() {
    size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '-' ||
                              s_[i_] == '_' || s_[i_] == ':' || s_[i_] == '.'))
      ++i_;
    if (i_ == start) fail("expected a name");
    return s_.substr(start, i_ - start);
  }
  void text_until(char stop) {
    while (i_ < s_.size() && s_[i_] != stop) {
      if (s_[i_] == '<') fail("'<' in text or attribute");
      if (s_[i_] == '&') {
        size_t semi = s_.find(';', i_);
        if (semi == std::string::npos) fail("unterminated entity");
        std::string e = s_.substr(i_ + 1, semi - i_ - 1);
        if (e != "amp" && e != "lt" && e != "gt" && e != "quot" && e != "apos" &&
            (e.empty() || e[0] != '#'))
          fail("unknown entity &" + e + ";");
        i_ = semi;
      }
      ++i_;
    }
  }
  void element() {
    ++i_;  // '<'
    XmlElement el;
    el.name = name();
    for (;;) {
      skip_space();
      if (i_ >= s_.size()) fail("unterminated start tag <" + el.name);
      if (s_[i_] == '/' || s_[i_] == '>') break;
      std::string attr = name();
      skip_space();
      if (i_ >= s_.size() || s_[i_] != '=') fail("attribute " + attr + " without a value");
      ++i_;
      skip_space();
      if (i_ >= s_.size() || (s_[i_] != '"' && s_[i_] != '\'')) fail("unquoted attribute " + attr);
      char quote = s_[i_++];
      size_t start = i_;
      text_until(quote);
      if (i_ >= s_.size()) fail("unterminated attribute " + attr);
      if (!el.attributes.emplace(attr, s_.substr(start, i_ - start)).second)
        fail("duplicate attribute " + attr);
      ++i_;
    }
    elements_.push_back(el);
    if (s_[i_] == '/') {
      if (s_.compare(i_, 2, "/>") != 0) fail("bad empty-element tag");
      i_ += 2;
      return;
    }
    ++i_;  // '>'
    for (;;) {
      text_until('<');
      if (i_ >= s_.size()) fail("<" + el.name + "> never closed");
      if (s_.compare(i_, 4, "<!--") == 0) {
        skip_misc();
        continue;
      }
      if (s_.compare(i_, 2, "</") == 0) {
        i_ += 2;
        std::string closing = name();
        if (closing != el.name) fail("</" + closing + "> closes <" + el.name + ">");
        skip_space();
        if (i_ >= s_.size() || s_[i_] != '>') fail("bad end tag");
        ++i_;
        return;
      }
      element();
    }
  }

  const std::string& s_;
  size_t i_ = 0;
  std::vector<XmlElement> elements_;
};

}  // namespace stepnode::tools::testing
