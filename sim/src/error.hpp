// The one error type of the simulator's C++ inside: a status from qnav/sim.h and a
// one-line message ("FILE:LINE: problem" or "FIELD: problem") that the C API copies out.
#pragma once

#include <stdexcept>
#include <string>

#include "qnav/sim.h"

namespace qnav {

class SimError : public std::runtime_error {
public:
    SimError(qnav_sim_status_t status, const std::string &message)
        : std::runtime_error(message), status_(status) {}
    qnav_sim_status_t status() const { return status_; }

private:
    qnav_sim_status_t status_;
};

}  // namespace qnav
