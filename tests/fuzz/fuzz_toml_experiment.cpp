// libFuzzer target: simevo's experiment file reader (host/simevo/src/spec.cpp,
// parse_experiment), then every preset applied to what it read. Property beyond "no crash,
// no sanitizer report": a file either loads or is refused with qnav::UserError, whose
// message is one line naming the file; any other exception escaping is a defect. (Robot,
// environment and policy files an experiment names are checked later, on disk, by
// load_run_spec: not here.)
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "spec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char *>(data), size);
    try {
        qnav::ExperimentSpec spec = qnav::parse_experiment(text, "fuzz.toml");
        for (const auto &preset : spec.presets) {
            qnav::ExperimentSpec copy = spec;
            qnav::apply_preset(copy, preset.first);
        }
    } catch (const qnav::UserError &e) {
        if (std::strncmp(e.what(), "fuzz.toml", 9) != 0 || std::strchr(e.what(), '\n') != nullptr) {
            std::abort();
        }
    }
    return 0;
}
