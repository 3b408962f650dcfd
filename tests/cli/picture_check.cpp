// afb_picture_check: checks the pictures `afb draw` writes (used by tests/cli/draw.cmake).
//   afb_picture_check png FILE                  PNG signature, IHDR size equal to the decoded size, not
//   blank: more
//                                               than one colour in the middle of the picture (where the
//                                               bodies are)
//   afb_picture_check svg FILE                  well-formed XML (expat) whose root is <svg> with a width and
//   height afb_picture_check same A.png B.png TOP TOL  same size, and every pixel below row TOP within TOL
//   per channel
//   afb_picture_check colour FILE RRGGBB PCT    at least PCT % of all pixels exactly colour RRGGBB (hex)
// Exit code 0 when the check holds; otherwise 1 with the reason on stderr.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <cairo.h>
#include <expat.h>

namespace {

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;

int fail(const std::string& message) {
    std::fprintf(stderr, "picture_check: %s\n", message.c_str());
    return 1;
}

std::vector<unsigned char> readFile(const char* path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::uint32_t bigEndian32(const std::vector<unsigned char>& b, std::size_t at) {
    return std::uint32_t(b[at]) << 24 | std::uint32_t(b[at + 1]) << 16 | std::uint32_t(b[at + 2]) << 8 | b[at + 3];
}

SurfacePtr decode(const char* path) {
    SurfacePtr s(cairo_image_surface_create_from_png(path), cairo_surface_destroy);
    if (cairo_surface_status(s.get()) != CAIRO_STATUS_SUCCESS) return {nullptr, cairo_surface_destroy};
    cairo_surface_flush(s.get());
    return s;
}

// Pixel (x, y) as 0xRRGGBB; cairo decodes to ARGB32 or RGB24, both 32 bits per pixel, native endian.
std::uint32_t pixel(cairo_surface_t* s, int x, int y) {
    const unsigned char* row = cairo_image_surface_get_data(s) + y * cairo_image_surface_get_stride(s);
    std::uint32_t value;
    std::memcpy(&value, row + 4 * x, 4);
    return value & 0xFFFFFFu;
}

int checkPng(const char* path) {
    const std::vector<unsigned char> bytes = readFile(path);
    static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (bytes.size() < 33 || !std::equal(kSignature, kSignature + 8, bytes.begin()))
        return fail(std::string(path) + ": no PNG signature");
    if (std::string(bytes.begin() + 12, bytes.begin() + 16) != "IHDR") return fail("the first chunk is not IHDR");
    const std::uint32_t width = bigEndian32(bytes, 16), height = bigEndian32(bytes, 20);
    if (width < 100 || height < 100 || width > 10000 || height > 10000)
        return fail("implausible size " + std::to_string(width) + " x " + std::to_string(height));
    const SurfacePtr image = decode(path);
    if (!image) return fail(std::string(path) + ": cairo cannot decode it");
    const int w = cairo_image_surface_get_width(image.get()), h = cairo_image_surface_get_height(image.get());
    if (std::uint32_t(w) != width || std::uint32_t(h) != height) return fail("IHDR size differs from the pixels");
    std::set<std::uint32_t> colours;
    long inked = 0, total = 0;
    for (int y = h / 3; y < 2 * h / 3; ++y)
        for (int x = w / 3; x < 2 * w / 3; ++x) {
            const std::uint32_t p = pixel(image.get(), x, y);
            colours.insert(p);
            inked += p != 0xFFFFFFu;
            ++total;
        }
    std::printf("%s: PNG %u x %u, %zu colours and %.1f%% non-white pixels in the middle third\n", path, width, height,
                colours.size(), 100.0 * double(inked) / double(total));
    if (colours.size() < 2) return fail("blank: one colour in the middle of the picture");
    return 0;
}

struct SvgState {
    int elements = 0;
    std::string root;
    bool rootHasSize = false;
};

int checkSvg(const char* path) {
    const std::vector<unsigned char> bytes = readFile(path);
    if (bytes.empty()) return fail(std::string(path) + ": empty or missing");
    std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate(nullptr), XML_ParserFree);
    SvgState state;
    XML_SetUserData(parser.get(), &state);
    XML_SetStartElementHandler(parser.get(), [](void* data, const XML_Char* name, const XML_Char** attributes) {
        auto& s = *static_cast<SvgState*>(data);
        if (s.elements++ > 0) return;
        s.root = name;
        int sizes = 0;
        for (int i = 0; attributes[i]; i += 2)
            sizes += std::string(attributes[i]) == "width" || std::string(attributes[i]) == "height";
        s.rootHasSize = sizes == 2;
    });
    if (XML_Parse(parser.get(), reinterpret_cast<const char*>(bytes.data()), static_cast<int>(bytes.size()), 1) !=
        XML_STATUS_OK)
        return fail(std::string(path) + ":" + std::to_string(XML_GetCurrentLineNumber(parser.get())) + ": " +
                    XML_ErrorString(XML_GetErrorCode(parser.get())));
    if (state.root != "svg" || !state.rootHasSize) return fail("the root element is not <svg width height>");
    std::printf("%s: SVG, %d elements\n", path, state.elements);
    if (state.elements < 10) return fail("almost empty SVG");
    return 0;
}

int checkSame(const char* a, const char* b, int top, int tolerance) {
    const SurfacePtr x = decode(a), y = decode(b);
    if (!x || !y) return fail("cannot decode both pictures");
    const int w = cairo_image_surface_get_width(x.get()), h = cairo_image_surface_get_height(x.get());
    if (w != cairo_image_surface_get_width(y.get()) || h != cairo_image_surface_get_height(y.get()))
        return fail("the pictures differ in size");
    long differing = 0;
    int worst = 0, left = w, right = -1, first = h, last = -1; // the box around the differing pixels
    for (int row = top; row < h; ++row)
        for (int col = 0; col < w; ++col) {
            const std::uint32_t p = pixel(x.get(), col, row), q = pixel(y.get(), col, row);
            for (int shift : {0, 8, 16}) {
                const int d = std::abs(int((p >> shift) & 0xFF) - int((q >> shift) & 0xFF));
                worst = std::max(worst, d);
                differing += d > 0;
            }
            if (p != q) {
                left = std::min(left, col);
                right = std::max(right, col);
                first = std::min(first, row);
                last = std::max(last, row);
            }
        }
    std::printf("%s vs %s below row %d: %ld channel values differ, by at most %d", a, b, top, differing, worst);
    if (differing > 0) std::printf(" (within x %d..%d, y %d..%d)", left, right, first, last);
    std::printf("\n");
    if (worst > tolerance) return fail("the pictures differ by more than " + std::to_string(tolerance));
    return 0;
}

int checkColour(const char* path, const char* hex, double minPercent) {
    const SurfacePtr image = decode(path);
    if (!image) return fail(std::string(path) + ": cannot decode it");
    const auto colour = static_cast<std::uint32_t>(std::strtoul(hex, nullptr, 16));
    const int w = cairo_image_surface_get_width(image.get()), h = cairo_image_surface_get_height(image.get());
    long count = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) count += pixel(image.get(), x, y) == colour;
    const double percent = 100.0 * double(count) / (double(w) * double(h));
    std::printf("%s: %.1f%% of the pixels are #%06x\n", path, percent, colour);
    if (percent < minPercent) return fail("fewer than " + std::to_string(minPercent) + "% of the pixels");
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "png" && argc == 3) return checkPng(argv[2]);
    if (mode == "svg" && argc == 3) return checkSvg(argv[2]);
    if (mode == "same" && argc == 6) return checkSame(argv[2], argv[3], std::atoi(argv[4]), std::atoi(argv[5]));
    if (mode == "colour" && argc == 5) return checkColour(argv[2], argv[3], std::atof(argv[4]));
    return fail(
        "usage: afb_picture_check png FILE | svg FILE | same A.png B.png SKIP_TOP TOLERANCE | colour FILE RRGGBB PCT");
}
