// Which body takes the impacts on each md5 joint (docs/format.md §5.3).
#include <algorithm>
#include <map>
#include <sstream>

#include "FigureBuilder.h"

namespace afb::figure::detail {

// §5.3: containedJoints ("*origin" when omitted); later bodies win overlaps.
void Builder::mapContainedJoints() {
    const int n = m_skel.jointCount();
    m_figure.jointBody.assign(static_cast<std::size_t>(n), -1);
    for (std::size_t k = 0; k < m_work.size(); ++k) {
        const AfBody& b = *m_work[k].decl;
        std::vector<bool> mine(static_cast<std::size_t>(n), false);
        std::istringstream words(b.containedJoints.value_or("*origin"));
        std::string word;
        while (words >> word) {
            bool remove = false, all = false;
            std::string name = word;
            if (!name.empty() && name[0] == '-') {
                remove = true;
                name.erase(0, 1);
            }
            if (!name.empty() && name[0] == '*') {
                all = true;
                name.erase(0, 1);
            }
            const std::optional<int> j = m_skel.findJoint(name);
            if (!j) {
                warning(b.location, "body '" + b.name + "': containedJoints names unknown joint \"" + name +
                                        "\"; the entry is skipped");
                continue;
            }
            const std::vector<int> joints = all ? m_skel.jointAndDescendants(*j) : std::vector<int>{*j};
            for (int x : joints) mine[static_cast<std::size_t>(x)] = !remove;
        }
        std::map<int, std::string> takenFrom; // previous owner -> joints this body takes over
        for (int j = 0; j < n; ++j) {
            if (!mine[static_cast<std::size_t>(j)]) continue;
            int& owner = m_figure.jointBody[static_cast<std::size_t>(j)];
            if (owner >= 0) {
                std::string& list = takenFrom[owner];
                list += (list.empty() ? "" : ", ") + m_skel.name(j);
            }
            owner = static_cast<int>(k);
            m_figure.bodies[k].containedJoints.push_back(j);
        }
        for (const auto& [owner, joints] : takenFrom)
            warning(b.location, "body '" + b.name + "' contains joints that body '" +
                                    m_figure.bodies[static_cast<std::size_t>(owner)].name + "' contains too (" +
                                    joints + "); the later body '" + b.name + "' takes their impacts");
    }
    for (auto& body : m_figure.bodies) {
        std::sort(body.containedJoints.begin(), body.containedJoints.end());
        body.containedJoints.erase(std::unique(body.containedJoints.begin(), body.containedJoints.end()),
                                   body.containedJoints.end());
    }
    for (FigureBody& body : m_figure.bodies)
        std::erase_if(body.containedJoints, [&](int j) {
            return m_figure.jointBody[static_cast<std::size_t>(j)] != &body - m_figure.bodies.data();
        });
    std::string uncontained;
    int count = 0;
    for (int j = 0; j < n; ++j)
        if (m_figure.jointBody[static_cast<std::size_t>(j)] < 0) {
            if (count < 8) uncontained += (count ? ", " : "") + m_skel.name(j);
            ++count;
        }
    if (count > 0)
        warning(m_decl.location, std::to_string(count) + " joint(s) contained by no body (" + uncontained +
                                     (count > 8 ? ", ..." : "") + "): impacts on them are ignored");
}

} // namespace afb::figure::detail
