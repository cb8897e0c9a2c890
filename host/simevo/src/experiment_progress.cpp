/*
 * The progress line (docs/cli.md, "Progress"): how it is shortened to fit the terminal,
 * and the Progress counter whose printer thread redraws it.
 */
#include "experiment_progress.h"

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <set>

#include "qnav/terminal.hpp"

namespace qnav {

namespace {


/* "m:ss", or "h:mm:ss" from an hour on. */
std::string eta_text(long s)
{
    char b[48];
    if (s >= 3600) {
        std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
    } else {
        std::snprintf(b, sizeof b, "%ld:%02ld", s / 60, s % 60);
    }
    return b;
}

/* label with its leading words cut to their first letter ("transfer-open" -> "t-open");
 * words that start with a digit are kept ("8-sectors"). */
std::string abbreviate_label(const std::string &label)
{
    std::string out;
    std::size_t start = 0;
    for (;;) {
        const std::size_t dash = label.find('-', start);
        const std::string word = label.substr(start, dash == std::string::npos ? std::string::npos : dash - start);
        if (dash == std::string::npos) {
            return out + word;
        }
        const bool letters = !word.empty() && std::isalpha(static_cast<unsigned char>(word[0])) != 0;
        out += (letters ? word.substr(0, 1) : word) + "-";
        start = dash + 1;
    }
}

std::size_t columns_of(const std::string &s)
{
    std::size_t n = 0;
    for (char c : s) {
        n += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    }
    return n;
}

/* The progress line in at most columns - 1 characters. The best R of every condition is
 * what a reader watches, so when the whole line is too wide the other fields give way
 * first, least telling first: the experiment's name, the episode counts, the rate, the
 * percentage's decimal; then the labels are abbreviated ("t-open" for "transfer-open", when
 * still unique), "best R:" becomes "R:", R gets one decimal and the fields one space
 * between them. Only a line still too wide after all that is cut (docs/cli.md, "Progress"). */
std::string progress_line(const std::string &title, uint64_t done, uint64_t total, double rate, long eta_s,
                          const std::map<std::string, double> &best, int columns)
{
    const double pct = total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0;
    char b[160];
    std::set<std::string> short_labels;
    for (auto &kv : best) {
        short_labels.insert(abbreviate_label(kv.first));
    }
    const bool can_abbreviate = short_labels.size() == best.size();
    struct Shape {
        bool title, counts, rate, pct_decimal, abbreviated, short_head, r_decimal2, wide_gaps;
    };
    const Shape shapes[] = {
        {true, true, true, true, false, false, true, true},
        {false, true, true, true, false, false, true, true},
        {false, false, true, true, false, false, true, true},
        {false, false, false, true, false, false, true, true},
        {false, false, false, false, false, false, true, true},
        {false, false, false, false, can_abbreviate, false, true, true},
        {false, false, false, false, can_abbreviate, true, true, true},
        {false, false, false, false, can_abbreviate, true, false, false},
    };
    const std::size_t room = columns > 1 ? static_cast<std::size_t>(columns - 1) : 1;
    std::string line;
    for (const Shape &sh : shapes) {
        const char *gap = sh.wide_gaps ? "  " : " ";
        line.clear();
        if (sh.title) {
            line += "[" + title + "] ";
        }
        if (sh.counts) {
            std::snprintf(b, sizeof b, "%" PRIu64 "/%" PRIu64 " episodes%s", done, total, gap);
            line += b;
        }
        // whole percent rounded down: "100%" only when every episode is done
        std::snprintf(b, sizeof b, sh.pct_decimal ? "%.1f%%%s" : "%.0f%%%s", sh.pct_decimal ? pct : std::floor(pct), gap);
        line += b;
        if (sh.rate) {
            std::snprintf(b, sizeof b, "%.0f ep/s%s", rate, gap);
            line += b;
        }
        // once every episode is done there is no time left to tell
        line += total != 0 && done >= total ? "done" : "ETA " + eta_text(eta_s);
        if (!best.empty()) {
            line += gap;
            line += sh.short_head ? "R:" : "best R:";
        }
        for (auto &kv : best) {
            std::snprintf(b, sizeof b, sh.r_decimal2 ? " %.2f" : " %.1f", kv.second);
            line += " " + (sh.abbreviated ? abbreviate_label(kv.first) : kv.first) + b;
        }
        if (columns_of(line) <= room) {
            return line;
        }
    }
    return qnav::cli::fit_line(line, columns);
}

} // namespace

Progress::Progress(uint64_t total, bool enabled, std::string title)
    : total_(total), enabled_(enabled), title_(std::move(title)),
      t0_(std::chrono::steady_clock::now())
{
    if (enabled_) {
        printer_ = std::thread([this] { loop(); });
    }
}

Progress::~Progress() { finish(); }

void Progress::finish()
{
    {
        std::lock_guard<std::mutex> l(mu_);
        if (finished_) {
            return;
        }
        finished_ = true;
    }
    cv_.notify_all();
    if (printer_.joinable()) {
        printer_.join();
        print_line();
        std::fputc('\n', stderr);
    }
}

void Progress::add(uint64_t n, bool replayed)
{
    done_ += n;
    if (replayed) {
        replayed_ += n;
    }
}

void Progress::best(const std::string &label, double r)
{
    std::lock_guard<std::mutex> l(mu_);
    // A label names a condition, not a run: keep the best over all its runs.
    auto it = best_.find(label);
    if (it == best_.end() || r > it->second) {
        best_[label] = r;
    }
}

void Progress::loop()
{
    std::unique_lock<std::mutex> l(mu_);
    while (!finished_) {
        cv_.wait_for(l, std::chrono::milliseconds(500));
        if (finished_) {
            break;
        }
        l.unlock();
        print_line();
        l.lock();
    }
}

void Progress::print_line()
{
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    const uint64_t done = done_.load();
    const uint64_t fresh = done - replayed_.load();
    const double rate = secs > 0 ? static_cast<double>(fresh) / secs : 0.0;
    const double left = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : 0.0;
    std::map<std::string, double> bests;
    {
        std::lock_guard<std::mutex> l(mu_);
        bests = best_;
    }
    // fitted to the terminal (asked each time: it may be resized): a wrapped line would
    // scroll instead of being redrawn in place
    const std::string line = progress_line(title_, done, total_, rate, static_cast<long>(left), bests,
                                           qnav::cli::terminal_columns(2));
    std::fprintf(stderr, "\r\033[K%s", line.c_str());
    std::fflush(stderr);
}

} // namespace qnav
