// Input errors that name where the bad input is: file, field (JSON pointer / XML path) and,
// when known, the line. Every loader throws SceneError; apps print what() and exit non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace lpt {

/// A library's message made one line: line breaks become "; " and trailing ones go, so every
/// error stays one line that names the file first (libpng, tinygltf and OpenImageIO write several).
inline std::string one_line(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] != '\n' && s[i] != '\r') {
            out += s[i];
            continue;
        }
        while (i + 1 < s.size() && (s[i + 1] == '\n' || s[i + 1] == '\r')) ++i;
        out += "; ";
    }
    return out;
}

class SceneError : public std::runtime_error {
public:
    SceneError(const std::string& file, const std::string& field, const std::string& message, int line = -1)
        : std::runtime_error(format(file, field, message, line)),
          m_file(file),
          m_field(field),
          m_message(message),
          m_line(line) {}
    const std::string& file() const { return m_file; }
    const std::string& field() const { return m_field; }
    /// The message alone, without file, line and field.
    const std::string& message() const { return m_message; }
    /// The same error with `more` appended to its message (e.g. which shapes use a material).
    SceneError with_note(const std::string& more) const {
        return SceneError(m_file, m_field, m_message + more, m_line);
    }

private:
    static std::string format(const std::string& file, const std::string& field, const std::string& msg, int line) {
        std::string s = file;
        if (line >= 0) s += ":" + std::to_string(line);
        if (!field.empty()) s += ": field '" + field + "'";
        return s + ": " + one_line(msg);
    }
    std::string m_file, m_field, m_message;
    int m_line;
};

}  // namespace lpt
