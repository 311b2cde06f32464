#pragma once
// The one error type for bad user input: it names the file and the place in it.
//
// what() reads "FILE:LINE: message", "FILE: at /json/path: message" or "FILE: message", so every
// command prints the same shape of diagnostic and exits with code 2.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace twinray {

class InputError : public std::runtime_error {
 public:
  // `where` is a location inside the file: "line 12", "/shapes/3/radius", "byte 1024", or empty.
  InputError(const std::filesystem::path& file, const std::string& where, const std::string& message)
      : std::runtime_error(format(file, where, message)), file_(file), where_(where), message_(message) {}

  const std::filesystem::path& file() const { return file_; }
  const std::string& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  static std::string format(const std::filesystem::path& file, const std::string& where, const std::string& msg) {
    std::string s = file.empty() ? std::string("<input>") : file.string();
    if (where.rfind("line ", 0) == 0) {
      s.append(":").append(where, 5, std::string::npos);
    } else if (!where.empty()) {
      s.append(": at ").append(where);
    }
    s.append(": ").append(msg);
    return s;
  }

  std::filesystem::path file_;
  std::string where_;
  std::string message_;
};

}  // namespace twinray
