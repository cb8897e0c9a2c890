/*
 * The progress line of a running experiment: episodes done of the total, rate, ETA and
 * the best R of every condition, redrawn on stderr twice a second and fitted to the
 * terminal's width (docs/cli.md, "Progress"). Private to the experiment's task pool.
 */
#ifndef QNAV_SIMEVO_EXPERIMENT_PROGRESS_H
#define QNAV_SIMEVO_EXPERIMENT_PROGRESS_H

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>

namespace qnav {

/* Counts episodes (add) and each condition's best R (best) from any thread; when enabled,
 * a printer thread redraws the line until finish() (or the destructor) draws it a last
 * time and ends it with a newline. */
class Progress {
public:
    Progress(uint64_t total, bool enabled, std::string title);
    ~Progress();

    void finish();
    void add(uint64_t n, bool replayed);
    void best(const std::string &label, double r);

private:
    void loop();
    void print_line();

    std::atomic<uint64_t> done_{0}, replayed_{0};
    uint64_t total_;
    bool enabled_;
    std::string title_;
    std::chrono::steady_clock::time_point t0_;
    std::mutex mu_;
    std::condition_variable cv_;
    bool finished_ = false;
    std::map<std::string, double> best_;
    std::thread printer_;
};

} // namespace qnav

#endif
