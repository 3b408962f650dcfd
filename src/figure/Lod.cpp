// Levels of detail (Lod.h): partitions of a figure's bodies.
#include "afb/figure/Lod.h"

#include <algorithm>
#include <numeric>

namespace afb::figure {
namespace {

// Union–find over the bodies; the root of a set is its smallest body.
class Groups {
  public:
    explicit Groups(std::size_t n) : m_root(n) { std::iota(m_root.begin(), m_root.end(), 0); }
    int find(int b) const {
        while (m_root[static_cast<std::size_t>(b)] != b) b = m_root[static_cast<std::size_t>(b)];
        return b;
    }
    void join(int a, int b) {
        a = find(a);
        b = find(b);
        m_root[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
    LodLevel level() const {
        LodLevel out;
        std::vector<int> index(m_root.size(), -1);
        for (std::size_t i = 0; i < m_root.size(); ++i) {
            const int r = find(static_cast<int>(i));
            if (index[static_cast<std::size_t>(r)] < 0) {
                index[static_cast<std::size_t>(r)] = static_cast<int>(out.groups.size());
                out.groups.emplace_back();
            }
            out.groups[static_cast<std::size_t>(index[static_cast<std::size_t>(r)])].push_back(static_cast<int>(i));
        }
        return out;
    }

  private:
    std::vector<int> m_root;
};

Groups fixedGroups(const Figure& f) {
    Groups g(f.bodies.size());
    for (const FigureConstraint& c : f.constraints)
        if (c.type == JointType::Fixed && c.body2 >= 0) g.join(c.body1, c.body2);
    return g;
}

// Whether `bodies` are connected by the figure's constraints between two of them.
bool connected(const Figure& f, const std::vector<int>& bodies) {
    Groups g(f.bodies.size());
    const auto in = [&](int b) { return std::find(bodies.begin(), bodies.end(), b) != bodies.end(); };
    for (const FigureConstraint& c : f.constraints)
        if (c.body2 >= 0 && in(c.body1) && in(c.body2)) g.join(c.body1, c.body2);
    return std::all_of(bodies.begin(), bodies.end(), [&](int b) { return g.find(b) == g.find(bodies.front()); });
}

} // namespace

std::variant<LodLevel, std::string> lodFromNames(const Figure& f, const std::vector<std::vector<std::string>>& names) {
    Groups g = fixedGroups(f);
    std::vector<char> named(f.bodies.size(), 0);
    for (const std::vector<std::string>& group : names) {
        std::vector<int> bodies;
        for (const std::string& name : group) {
            const auto it =
                std::find_if(f.bodies.begin(), f.bodies.end(), [&](const FigureBody& b) { return b.name == name; });
            if (it == f.bodies.end()) return "LOD: no body \"" + name + "\" in figure " + f.name;
            const int b = static_cast<int>(it - f.bodies.begin());
            if (named[static_cast<std::size_t>(b)]) return "LOD: body \"" + name + "\" is named more than once";
            named[static_cast<std::size_t>(b)] = 1;
            bodies.push_back(b);
        }
        if (bodies.empty()) continue;
        if (!connected(f, bodies)) {
            std::string list;
            for (const std::string& name : group) list += (list.empty() ? "" : ", ") + name;
            return "LOD: the group (" + list + ") is not connected by constraints between its bodies";
        }
        for (const int b : bodies) g.join(b, bodies.front());
    }
    return g.level();
}

LodLevel automaticLod(const Figure& f, int targetBodies) {
    Groups g = fixedGroups(f);
    LodLevel level = g.level();
    const auto massOf = [&](const std::vector<int>& group) {
        double m = 0;
        for (const int b : group) m += f.bodies[static_cast<std::size_t>(b)].massKg;
        return m;
    };
    while (static_cast<int>(level.groups.size()) > std::max(1, targetBodies)) {
        const std::size_t n = level.groups.size();
        std::vector<int> groupOf(f.bodies.size());
        std::vector<double> mass(n);
        for (std::size_t k = 0; k < n; ++k) {
            mass[k] = massOf(level.groups[k]);
            for (const int b : level.groups[k]) groupOf[static_cast<std::size_t>(b)] = static_cast<int>(k);
        }
        // Groups in merge order (lightest first; the groups are ordered by first body, so ties go to the lower).
        std::vector<std::size_t> order(n);
        std::iota(order.begin(), order.end(), std::size_t{0});
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mass[a] < mass[b]; });
        bool merged = false;
        for (const std::size_t k : order) {
            int best = -1;
            for (const FigureConstraint& c : f.constraints) {
                if (c.body2 < 0) continue;
                const int a = groupOf[static_cast<std::size_t>(c.body1)],
                          b = groupOf[static_cast<std::size_t>(c.body2)];
                if (a == b || (a != static_cast<int>(k) && b != static_cast<int>(k))) continue;
                const int other = a == static_cast<int>(k) ? b : a;
                if (best < 0 || mass[static_cast<std::size_t>(other)] < mass[static_cast<std::size_t>(best)] ||
                    (mass[static_cast<std::size_t>(other)] == mass[static_cast<std::size_t>(best)] && other < best))
                    best = other;
            }
            if (best < 0) continue; // no neighbour: try the next lightest
            g.join(level.groups[k].front(), level.groups[static_cast<std::size_t>(best)].front());
            merged = true;
            break;
        }
        if (!merged) break;
        level = g.level();
    }
    return level;
}

} // namespace afb::figure
