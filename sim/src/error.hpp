// The one error type of the simulator's C++ inside: a status from qnav/sim.h and a
// one-line message ("FILE:LINE: problem" or "FIELD: problem") that the C API copies out;
// control characters quoted from the input are escaped (one_line()).
#pragma once

#include <stdexcept>
#include <string>

#include "qnav/one_line.hpp"
#include "qnav/sim.h"

namespace qnav {

class SimError : public std::runtime_error {
public:
    SimError(qnav_sim_status_t status, const std::string &message)
        : std::runtime_error(one_line(message)), status_(status) {}
    qnav_sim_status_t status() const { return status_; }

private:
    qnav_sim_status_t status_;
};

}  // namespace qnav
