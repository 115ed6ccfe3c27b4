// The pre-scan of STEP/IGES text: see prescan.h.
#include "importer/prescan.h"

#include <cctype>
#include <fstream>
#include <istream>
#include <vector>

#include "core/error.h"

namespace nurbsrt {
namespace {

constexpr size_t kChunkBytes = 1 << 16;

// `what` holds the limit: "more than 500000 items".
[[noreturn]] void refuse(const std::string& what) {
    throw Error(ErrorCode::unreadable_file,
                "the file holds " + what + " (the limit); it is refused before it is parsed");
}

std::string more_than(size_t limit, const char* unit) { return "more than " + std::to_string(limit) + " " + unit; }

// ISO 10303-21 text as a stream of characters: strings ('...', '' inside one is
// a quote, which this toggling handles) and comments (/* ... */) are skipped.
class StepScanner {
public:
    explicit StepScanner(const PrescanLimits& limits) : limits_(limits) { open_.reserve(64); }

    void feed(const char* p, size_t n) {
        for (size_t i = 0; i < n; ++i) step(p[i]);
    }
    const PrescanReport& report() const { return report_; }

private:
    struct List {
        size_t commas = 0;
        bool content = false;
    };

    void step(char c) {
        const char prev = prev_;
        prev_ = c;
        if (in_comment_) {
            if (prev == '*' && c == '/') in_comment_ = false, prev_ = 0;
            return;
        }
        if (in_string_) {
            if (c == '\'') in_string_ = false;
            return;
        }
        if (prev == '/' && c == '*') {
            in_comment_ = true;
            prev_ = 0;
            return;
        }
        if (!open_.empty() && !std::isspace(static_cast<unsigned char>(c)) && c != ')') open_.back().content = true;
        switch (c) {
            case '\'':
                in_string_ = true;
                break;
            case '(':
                open_.push_back({});
                if (static_cast<int>(open_.size()) > report_.deepest_nesting) {
                    report_.deepest_nesting = static_cast<int>(open_.size());
                    if (report_.deepest_nesting > limits_.max_nesting)
                        refuse("parentheses nested " +
                               more_than(static_cast<size_t>(limits_.max_nesting), "levels deep"));
                }
                break;
            case ',':
                if (!open_.empty()) note_items(++open_.back().commas + 1);
                break;
            case ')':
                if (!open_.empty()) {
                    if (open_.back().content) note_items(open_.back().commas + 1);
                    open_.pop_back();
                }
                break;
            case '=':  // only an instance name (#12=...) has one outside strings
                if (open_.empty() && ++report_.entities > limits_.max_entities)
                    refuse(more_than(limits_.max_entities, "entities"));
                break;
            default:
                break;
        }
    }

    void note_items(size_t items) {
        if (items <= report_.longest_list) return;
        report_.longest_list = items;
        if (items > limits_.max_list_items) refuse("a list of " + more_than(limits_.max_list_items, "items"));
    }

    const PrescanLimits& limits_;
    PrescanReport report_;
    std::vector<List> open_;
    bool in_string_ = false, in_comment_ = false;
    char prev_ = 0;
};

// IGES 5.3 fixed-format records: column 73 is the section letter (S, G, D, P,
// T); parameter data are the first 64 columns of P records. Hollerith strings
// (nHtext) may hold delimiters and are skipped.
class IgesScanner {
public:
    explicit IgesScanner(const PrescanLimits& limits) : limits_(limits) {}

    void feed(const char* p, size_t n) {
        for (size_t i = 0; i < n; ++i) {
            if (p[i] == '\n') {
                record();
                line_.clear();
            } else if (line_.size() < 200) {  // a record is 80 columns; longer lines are cut
                line_.push_back(p[i]);
            }
        }
    }
    const PrescanReport& finish() {
        if (!line_.empty()) record();
        return report_;
    }

private:
    void record() {
        if (!line_.empty() && line_.back() == '\r') line_.pop_back();
        if (line_.size() < 73) return;
        const char section = line_[72];
        if (section == 'G') {
            global_ += line_.substr(0, 72);
            if (global_.size() >= 8) delimiters_from_global();
        } else if (section == 'D') {
            if (++directory_lines_ % 2 == 0 && (report_.entities = directory_lines_ / 2) > limits_.max_entities)
                refuse(more_than(limits_.max_entities, "entities"));
        } else if (section == 'P') {
            for (size_t i = 0; i < 64; ++i) parameter_char(line_[i]);
        }
    }

    // "1H,,1H;," sets the parameter and record delimiters (IGES 5.3, 2.2.4.3.1-2);
    // an empty field keeps the defaults ',' and ';'.
    void delimiters_from_global() {
        if (global_done_) return;
        global_done_ = true;
        if (global_.compare(0, 2, "1H") == 0) {
            param_ = global_[2];
            if (global_.size() >= 7 && global_[3] == param_ && global_.compare(4, 2, "1H") == 0) record_ = global_[6];
        } else if (global_[0] == ',' && global_.size() >= 3 && global_.compare(1, 2, "1H") == 0) {
            record_ = global_[3];
        }
    }

    void parameter_char(char c) {
        if (hollerith_left_ > 0) {
            --hollerith_left_;
            return;
        }
        if (std::isdigit(static_cast<unsigned char>(c)) && field_start_) {
            count_ = count_ * 10 + static_cast<size_t>(c - '0');
            return;
        }
        if (c == 'H' && field_start_ && count_ > 0) {
            hollerith_left_ = count_;
            count_ = 0;
            field_start_ = false;
            return;
        }
        count_ = 0;
        if (c == param_) {
            field_start_ = true;
            if (++items_ > report_.longest_list) {
                report_.longest_list = items_;
                if (items_ > limits_.max_list_items)
                    refuse("an entity with " + more_than(limits_.max_list_items, "parameters"));
            }
        } else if (c == record_) {
            field_start_ = true;
            items_ = 1;
        } else if (c != ' ') {
            field_start_ = false;
        }
    }

    const PrescanLimits& limits_;
    PrescanReport report_;
    std::string line_, global_;
    bool global_done_ = false, field_start_ = true;
    char param_ = ',', record_ = ';';
    size_t directory_lines_ = 0, items_ = 1, count_ = 0, hollerith_left_ = 0;
};

template <class Scanner>
void feed_file(std::istream& in, Scanner& scanner) {
    std::vector<char> chunk(kChunkBytes);
    while (in) {
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        scanner.feed(chunk.data(), static_cast<size_t>(in.gcount()));
    }
    if (in.bad()) throw Error(ErrorCode::io, "cannot read the file");
}

}  // namespace

PrescanReport prescan_cad_file(const std::string& path, CadFormat format, const PrescanLimits& limits) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::io, "cannot open '" + path + "'");
    return prescan_cad_stream(in, format, limits);
}

PrescanReport prescan_cad_stream(std::istream& in, CadFormat format, const PrescanLimits& limits) {
    if (format == CadFormat::iges) {
        IgesScanner scanner(limits);
        feed_file(in, scanner);
        return scanner.finish();
    }
    StepScanner scanner(limits);
    feed_file(in, scanner);
    return scanner.report();
}

}  // namespace nurbsrt
