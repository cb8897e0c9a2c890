/*
 * The task pool: an experiment's tasks on a number of threads, each task locked (flock)
 * while it runs so several simevo processes can share one experiment, a transfer started
 * only once its source is done, the first failure stopping the rest.
 */
#include "experiment.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "experiment_progress.h"
#include "files.h"

namespace qnav {

namespace {

/* Holds flock on DIR/.lock for one task: any number of simevo processes may work on one
 * experiment, but never two on the same task (their journals would interleave). */
class TaskLock {
public:
    explicit TaskLock(const std::string &dir)
    {
        make_dirs(dir);
        const std::string path = join_path(dir, ".lock");
        fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd_ < 0 || ::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
            if (fd_ >= 0) {
                ::close(fd_);
            }
            throw UserError(dir + ": another simevo is running this task (or its .lock cannot be locked)");
        }
    }
    ~TaskLock() { ::close(fd_); }
    TaskLock(const TaskLock &) = delete;
    TaskLock &operator=(const TaskLock &) = delete;

private:
    int fd_ = -1;
};

/* A selected transfer whose source task is neither selected nor done cannot start. */
void check_sources_finished(const std::vector<TaskDef> &tasks, const std::vector<char> &selected)
{
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        const int src = tasks[i].source_task;
        if (!selected[i] || src < 0 || selected[static_cast<std::size_t>(src)]) {
            continue;
        }
        const TaskDef &s = tasks[static_cast<std::size_t>(src)];
        if (!file_exists(join_path(s.dir, "done"))) {
            throw UserError(tasks[i].dir + ": its source task " + s.dir +
                            " is not finished (run the share that holds it first, e.g. --stage 1)");
        }
    }
}

enum class TaskState { Pending, Running, Done, Failed };

/* The first pending task whose source task is done, or tasks.size() when none is ready
 * yet; any_pending says whether any task is pending at all. */
std::size_t next_ready_task(const std::vector<TaskDef> &tasks, const std::vector<TaskState> &state, bool &any_pending)
{
    std::size_t pick = tasks.size();
    any_pending = false;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        if (state[i] != TaskState::Pending) {
            continue;
        }
        any_pending = true;
        const int src = tasks[i].source_task;
        if (src < 0 || state[static_cast<std::size_t>(src)] == TaskState::Done) {
            pick = i;
            break;
        }
    }
    return pick;
}

/* Task t, seeded from its source task's best policy or its source policy file, run while
 * its lock is held. Returns whether it finished; error holds why it failed, if it threw. */
bool run_locked_task(const std::vector<TaskDef> &tasks, const TaskDef &t, const RunnerFactory &make,
                     const TaskObserver &obs, const std::atomic<bool> &stop, std::string &error)
{
    std::string source_path;
    if (t.source_task >= 0) {
        source_path = join_path(tasks[static_cast<std::size_t>(t.source_task)].dir, "best.policy");
    } else if (!t.source_policy_file.empty()) {
        source_path = t.source_policy_file;
    }
    bool ok = false;
    try {
        const TaskLock lock(t.dir);
        ok = run_task(t, source_path, make, obs, stop);
    } catch (const std::exception &e) {
        error = e.what();
    }
    return ok;
}

} // namespace

void run_tasks(const std::vector<TaskDef> &tasks, const RunnerFactory &make, unsigned jobs,
               bool progress, const std::string &title, std::vector<char> selected)
{
    if (selected.empty()) {
        selected.assign(tasks.size(), 1);
    }
    check_sources_finished(tasks, selected);
    uint64_t total = 0;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        total += selected[i] ? task_total_episodes(tasks[i]) : 0;
    }
    Progress prog(total, progress, title);
    TaskObserver obs;
    obs.episodes_done = [&prog](uint64_t n, bool replayed) { prog.add(n, replayed); };
    obs.best = [&prog](const std::string &label, double r) { prog.best(label, r); };

    std::vector<TaskState> state(tasks.size(), TaskState::Pending);
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        state[i] = selected[i] ? TaskState::Pending : TaskState::Done; // another share's (checked above)
    }
    std::mutex mu;
    std::condition_variable cv;
    std::atomic<bool> stop{false};
    std::string first_error;

    auto worker = [&]() {
        std::unique_lock<std::mutex> l(mu);
        for (;;) {
            if (stop.load()) {
                return;
            }
            bool any_pending = false;
            const std::size_t pick = next_ready_task(tasks, state, any_pending);
            if (!any_pending) {
                return;
            }
            if (pick == tasks.size()) {
                cv.wait(l);
                continue;
            }
            state[pick] = TaskState::Running;
            l.unlock();
            std::string error;
            const bool ok = run_locked_task(tasks, tasks[pick], make, obs, stop, error);
            l.lock();
            state[pick] = ok ? TaskState::Done : TaskState::Failed;
            if (!ok) {
                if (first_error.empty() && !error.empty()) {
                    first_error = error;
                }
                stop = true;
            }
            cv.notify_all();
        }
    };
    if (jobs == 0) {
        jobs = std::max(1u, std::thread::hardware_concurrency());
    }
    std::vector<std::thread> pool;
    for (unsigned i = 0; i < jobs; ++i) {
        pool.emplace_back(worker);
    }
    for (auto &th : pool) {
        th.join();
    }
    prog.finish();
    if (!first_error.empty()) {
        throw UserError(first_error);
    }
    if (stop.load()) {
        throw UserError(title + ": stopped before completion");
    }
}

} // namespace qnav
