// A minimal streaming JSON writer for reports: objects, arrays, strings, numbers, booleans, null.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace ndfbake {

class JsonWriter {
public:
    JsonWriter& begin_object(const char* key = nullptr) { open(key, '{'); return *this; }
    JsonWriter& end_object() { close('}'); return *this; }
    JsonWriter& begin_array(const char* key = nullptr) { open(key, '['); return *this; }
    JsonWriter& end_array() { close(']'); return *this; }

    JsonWriter& value(const char* key, const std::string& s) { prefix(key); quote(s); return *this; }
    JsonWriter& value(const char* key, const char* s) { return value(key, std::string(s)); }
    JsonWriter& value(const char* key, bool b) { prefix(key); out_ += b ? "true" : "false"; return *this; }
    JsonWriter& value(const char* key, int64_t i) { prefix(key); out_ += std::to_string(i); return *this; }
    JsonWriter& value(const char* key, uint64_t i) { prefix(key); out_ += std::to_string(i); return *this; }
    JsonWriter& value(const char* key, int i) { return value(key, int64_t(i)); }
    JsonWriter& value(const char* key, double d)
    {
        prefix(key);
        // JSON has no NaN or Inf; a non-finite figure is reported as null rather than a broken file.
        if (!std::isfinite(d)) { out_ += "null"; return *this; }
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, "%.6g", d);
        out_ += buffer;
        return *this;
    }
    JsonWriter& value(const char* key, float f) { return value(key, double(f)); }
    JsonWriter& null(const char* key) { prefix(key); out_ += "null"; return *this; }

    const std::string& str() const { return out_; }

private:
    void prefix(const char* key)
    {
        if (!first_.empty()) {
            if (!first_.back()) out_ += ',';
            first_.back() = false;
            out_ += '\n';
            out_.append(2 * first_.size(), ' ');
        }
        if (key) { quote(key); out_ += ": "; }
    }
    void open(const char* key, char bracket) { prefix(key); out_ += bracket; first_.push_back(true); }
    void close(char bracket)
    {
        const bool empty = first_.back();
        first_.pop_back();
        if (!empty) { out_ += '\n'; out_.append(2 * first_.size(), ' '); }
        out_ += bracket;
        if (first_.empty()) out_ += '\n';
    }
    void quote(const std::string& s)
    {
        out_ += '"';
        for (unsigned char c : s) {
            if (c == '"' || c == '\\') { out_ += '\\'; out_ += char(c); }
            else if (c == '\n') out_ += "\\n";
            else if (c < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); out_ += b; }
            else out_ += char(c);
        }
        out_ += '"';
    }

    std::string out_;
    std::vector<bool> first_;
};

}  // namespace ndfbake
