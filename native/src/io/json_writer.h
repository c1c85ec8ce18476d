// A minimal streaming JSON writer for reports: objects, arrays, strings, numbers, booleans, null.
// Strings are written as valid UTF-8 whatever the bytes given (file names are bytes on Linux).
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
    // JSON text must be UTF-8 (RFC 8259 §8.1), so strict readers (Python's json, jq) refuse a
    // report holding, say, a Latin-1 file name. Well-formed UTF-8 is copied as it is; every byte
    // that does not belong to a well-formed sequence becomes U+FFFD, written as the escape
    // \ufffd, as decoders replace bad bytes.
    void quote(const std::string& s)
    {
        out_ += '"';
        for (size_t i = 0; i < s.size();) {
            const unsigned char c = static_cast<unsigned char>(s[i]);
            if (c >= 0x80) {
                const size_t n = utf8_sequence_length(s, i);
                if (n == 0) { out_ += "\\ufffd"; ++i; }
                else { out_.append(s, i, n); i += n; }
                continue;
            }
            if (c == '"' || c == '\\') { out_ += '\\'; out_ += char(c); }
            else if (c == '\n') out_ += "\\n";
            else if (c < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); out_ += b; }
            else out_ += char(c);
            ++i;
        }
        out_ += '"';
    }

    // The length of the well-formed UTF-8 sequence that starts at s[i] (Unicode's table 3-7: no
    // overlong forms, no surrogates, nothing above U+10FFFF), or 0 where none does.
    static size_t utf8_sequence_length(const std::string& s, size_t i)
    {
        const auto byte = [&](size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
        const unsigned lead = byte(i);
        size_t n = 0;
        unsigned low = 0x80, high = 0xbf;  // what the second byte may be; later ones are 80..bf
        if (lead < 0x80) return 1;
        else if (lead >= 0xc2 && lead <= 0xdf) n = 2;
        else if (lead == 0xe0) n = 3, low = 0xa0;        // below: overlong
        else if (lead == 0xed) n = 3, high = 0x9f;       // above: UTF-16 surrogates
        else if (lead >= 0xe1 && lead <= 0xef) n = 3;
        else if (lead == 0xf0) n = 4, low = 0x90;        // below: overlong
        else if (lead >= 0xf1 && lead <= 0xf3) n = 4;
        else if (lead == 0xf4) n = 4, high = 0x8f;       // above: past U+10FFFF
        else return 0;                                   // 80..c1, f5..ff: never a lead byte
        if (byte(i + 1) < low || byte(i + 1) > high) return 0;
        for (size_t k = 2; k < n; ++k)
            if (byte(i + k) < 0x80 || byte(i + k) > 0xbf) return 0;
        return n;
    }

    std::string out_;
    std::vector<bool> first_;
};

}  // namespace ndfbake
