// libFuzzer target: the simulator's TOML readers (sim/src): a robot profile and an
// environment file, from the same input text. Property beyond "no crash, no sanitizer
// report": a file either loads or is refused with qnav::SimError, whose message is one
// line naming the file (docs/sim.md); any other exception escaping a reader is a defect.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "env.hpp"
#include "error.hpp"
#include "robot.hpp"

namespace {

void check_refusal(const qnav::SimError &e, const char *name)
{
    const char *what = e.what();
    if (std::strncmp(what, name, std::strlen(name)) != 0 || std::strchr(what, '\n') != nullptr) {
        std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size)
{
    const std::string_view text(reinterpret_cast<const char *>(data), size);
    try {
        (void)qnav::parse_robot_profile(text, "fuzz-robot.toml");
    } catch (const qnav::SimError &e) {
        check_refusal(e, "fuzz-robot.toml");
    }
    try {
        (void)qnav::parse_environment(text, "fuzz-env.toml");
    } catch (const qnav::SimError &e) {
        check_refusal(e, "fuzz-env.toml");
    }
    return 0;
}
