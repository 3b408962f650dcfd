// Reports of afb golden compare: JUnit XML, a Markdown summary, and pictures of failing poses.
#include "GoldenReport.h"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "Picture.h"
#include "afb/figure/Placement.h"

namespace afb::cli {
namespace {

// The length of the well-formed UTF-8 sequence at s[i], or 0 when there is none (RFC 3629: no overlong forms, no
// surrogates, nothing past U+10FFFF).
std::size_t utf8Length(const std::string& s, std::size_t i) {
    const auto byte = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
    const unsigned lead = byte(i);
    std::size_t n = 0;
    unsigned lo = 0x80, hi = 0xBF; // the allowed range of the second byte
    if (lead >= 0xC2 && lead <= 0xDF) n = 2;
    else if (lead >= 0xE0 && lead <= 0xEF) {
        n = 3;
        if (lead == 0xE0) lo = 0xA0;
        if (lead == 0xED) hi = 0x9F;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
        n = 4;
        if (lead == 0xF0) lo = 0x90;
        if (lead == 0xF4) hi = 0x8F;
    }
    if (n == 0 || byte(i + 1) < lo || byte(i + 1) > hi) return 0;
    for (std::size_t k = 2; k < n; ++k)
        if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
    return n;
}

// XML 1.0 text or attribute value: the five special characters escaped; what XML 1.0 cannot hold at all (control
// characters, bytes that are not UTF-8: a joint name is whatever bytes its file has) written as '?'.
std::string xmlEscaped(const std::string& s) {
    std::string out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        const char c = s[i];
        if (static_cast<unsigned char>(c) >= 0x80) {
            const std::size_t n = utf8Length(s, i);
            out += n == 0 ? std::string("?") : s.substr(i, n);
            i += n == 0 ? 0 : n - 1;
            continue;
        }
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        case '\'': out += "&apos;"; break;
        default: out += static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t' ? '?' : c;
        }
    }
    return out;
}

// A table cell of Markdown: pipes escaped, one line.
std::string mdCell(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '|') out += "\\|";
        else if (c == '\n' || c == '\r') out += ' ';
        else out += c;
    }
    return out;
}

std::string formatted(const char* fmt, double a, double b) {
    char buf[96];
    std::snprintf(buf, sizeof buf, fmt, a, b);
    return buf;
}

std::string missLine(const JointMiss& m) {
    char line[200];
    std::snprintf(line, sizeof line, "%s moved %.4f m, turned %.2f deg", m.joint.c_str(), m.movedM, m.turnedDeg);
    return line;
}

std::string joinedJoints(const GoldenCase& c) {
    std::string s;
    for (const JointMiss& m : c.missed) s += (s.empty() ? "" : ", ") + m.joint;
    return s;
}

// The failure message: what failed, in one line (the joints by name).
std::string failureMessage(const GoldenCase& c) {
    std::string msg;
    if (!c.missed.empty())
        msg = std::to_string(c.missed.size()) + (c.missed.size() == 1 ? " joint" : " joints") + " past tolerance (" +
              formatted("%.4f m / %.2f deg", c.toleranceM, c.toleranceDeg) + "): " + joinedJoints(c);
    for (const std::string& n : c.notes) msg += (msg.empty() ? "" : "; ") + n;
    return msg;
}

void writeCase(std::ostream& xml, const GoldenCase& c) {
    char time[32];
    std::snprintf(time, sizeof time, "%.3f", c.seconds);
    xml << "    <testcase name=\"" << xmlEscaped(c.file.generic_string()) << "\" classname=\"afb.golden."
        << xmlEscaped(c.entity.empty() ? "unknown" : c.entity) << "\" file=\"" << xmlEscaped(c.file.generic_string())
        << "\" time=\"" << time << "\"";
    if (c.passed) {
        xml << "/>\n";
        return;
    }
    xml << ">\n";
    if (!c.errors.empty()) {
        std::string text;
        for (const std::string& e : c.errors) text += e + "\n";
        xml << "      <error message=\"" << xmlEscaped(c.errors.front()) << "\" type=\"golden\">" << xmlEscaped(text)
            << "</error>\n";
    } else {
        std::string text = caseLine(c) + "\n";
        for (const JointMiss& m : c.missed) text += "  " + missLine(m) + "\n";
        xml << "      <failure message=\"" << xmlEscaped(failureMessage(c)) << "\" type=\"tolerance\">"
            << xmlEscaped(text) << "</failure>\n";
    }
    xml << "    </testcase>\n";
}

} // namespace

std::string caseLine(const GoldenCase& c) {
    std::string line = (c.passed ? "ok   " : "FAIL ") + c.file.string() + ": worst joint " +
                       formatted("%.4f m / %.2f deg", c.worstM, c.worstDeg) + " (tolerance " +
                       formatted("%.4f m / %.2f deg", c.toleranceM, c.toleranceDeg) + ")";
    for (const std::string& n : c.notes) line += ", " + n;
    return line;
}

std::optional<std::string> writeJUnit(const std::vector<GoldenCase>& cases, const std::filesystem::path& out) {
    std::size_t failures = 0, errors = 0;
    double seconds = 0;
    for (const GoldenCase& c : cases) {
        if (!c.passed) ++(c.errors.empty() ? failures : errors);
        seconds += c.seconds;
    }
    std::ostringstream xml;
    char time[32];
    std::snprintf(time, sizeof time, "%.3f", seconds);
    const std::string counts = "tests=\"" + std::to_string(cases.size()) + "\" failures=\"" + std::to_string(failures) +
                               "\" errors=\"" + std::to_string(errors) + "\"";
    xml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<testsuites name=\"afb golden compare\" " << counts << " time=\"" << time << "\">\n"
        << "  <testsuite name=\"afb golden compare\" " << counts << " skipped=\"0\" time=\"" << time << "\">\n";
    for (const GoldenCase& c : cases) writeCase(xml, c);
    xml << "  </testsuite>\n</testsuites>\n";
    if (out == "-") {
        std::cout << xml.str() << std::flush;
        return std::nullopt;
    }
    std::ofstream file(out);
    file << xml.str();
    if (!file.flush()) return out.string() + ": cannot be written";
    return std::nullopt;
}

std::optional<std::string> writeMarkdown(const std::vector<GoldenCase>& cases, const std::filesystem::path& dir) {
    std::size_t failed = 0, errors = 0;
    for (const GoldenCase& c : cases) {
        failed += !c.passed && c.errors.empty() ? 1 : 0;
        errors += c.errors.empty() ? 0 : 1;
    }
    std::ostringstream md;
    md << "# Golden comparison\n\n"
       << cases.size() << (cases.size() == 1 ? " golden: " : " goldens: ") << cases.size() - failed - errors
       << " passed, " << failed << " failed, " << errors << " could not be compared.\n\n"
       << "| golden | entity | result | worst joint | tolerance | past tolerance |\n"
       << "|---|---|---|---|---|---|\n";
    for (const GoldenCase& c : cases) {
        md << "| " << mdCell(c.file.generic_string()) << " | " << mdCell(c.entity) << " | "
           << (c.passed           ? "ok"
               : c.errors.empty() ? "**FAIL**"
                                  : "**ERROR**")
           << " | ";
        if (c.errors.empty())
            md << formatted("%.4f m / %.2f°", c.worstM, c.worstDeg) << " | "
               << formatted("%.4f m / %.2f°", c.toleranceM, c.toleranceDeg) << " | " << mdCell(failureMessage(c));
        else md << " |  | " << mdCell(c.errors.front());
        md << " |\n";
    }
    for (const GoldenCase& c : cases) {
        if (c.passed) continue;
        md << "\n## " << mdCell(c.file.generic_string()) << "\n\n";
        for (const std::string& e : c.errors) md << "- " << e << "\n";
        if (!c.picture.empty())
            md << "![" << mdCell(c.entity) << ": the settled pose (orange) over the golden pose (blue)]("
               << c.picture.generic_string() << ")\n\n";
        for (const JointMiss& m : c.missed) md << "- " << mdCell(missLine(m)) << "\n";
        for (const std::string& n : c.notes) md << "- " << n << "\n";
    }
    const std::filesystem::path out = dir / "summary.md";
    std::ofstream file(out);
    file << md.str();
    if (!file.flush()) return out.string() + ": cannot be written";
    return std::nullopt;
}

std::optional<std::string> drawGoldenPicture(const figure::Figure& figure, const PoseRecord& golden,
                                             const PoseRecord& now, const std::string& title,
                                             const std::string& subtitle, const std::filesystem::path& out) {
    const auto world = [](const PoseRecord& pose) {
        std::vector<figure::Transform> joints;
        for (const figure::Transform& j : pose.jointsModel) joints.push_back(pose.entity * j);
        return joints;
    };
    PictureRequest request;
    request.title = title;
    request.subtitle = subtitle;
    request.show = PictureLayers{true, false, false, false, true, false};
    request.bodies = figure::bodiesFromJoints(figure, now.entity, now.jointsModel);
    request.joints = world(now);
    request.groundZ = 0.0;
    request.reference = PictureReference{figure::bodiesFromJoints(figure, golden.entity, golden.jointsModel),
                                         world(golden), "golden pose (recorded)", "settled pose (now)"};
    return drawPicture(figure, request, out);
}

} // namespace afb::cli
