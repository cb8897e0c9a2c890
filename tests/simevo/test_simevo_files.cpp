/*
 * Tests of simevo's resumable outputs and of the program itself: a task stopped and
 * resumed (with a half-written journal line) ends with the same bytes as an uninterrupted
 * one; a journal from other settings is refused; the simevo program killed by its pid in
 * the middle of a run and started again ends with files identical to an uninterrupted
 * run; an experiment on 1 and 3 threads gives the same files and its summary matches
 * them; table mode and network mode give byte-identical results; and bad input (unknown
 * experiment, malformed spec, missing or incompatible policy file, a folder made with other
 * settings) gives one line and a non-zero exit without a summary (2 when found before any
 * work, 1 after). Also the defects of issue 11: temporary files never follow a planted
 * symlink, a plot script dies with simevo, zero episodes and NaN noise are refused, noise
 * above the simulator's 1 in a file fails at its line before any output, the progress
 * line fits the terminal (at 80 columns with every best R), unknown options and subcommands
 * are named. Sweeps (issue 12): a
 * sweep's shares merge to the files of its member experiment run directly with the same
 * --vary, `simevo slurm` writes each member's scripts and one submit.sh for all, and bad
 * sweep files fail at their line.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <regex> /* before cmocka.h, whose fail() macro it would meet */

extern "C" {
#include <cmocka.h>
}

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <algorithm>
#include <cerrno>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>
#include <pty.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fake_runner.h"
#include "files.h"
#include "qnav/policy_io.h"
#include "experiment.h"
#include "rng.h"
#include "spec.h"
#include "stats.h"
#include "task.h"

using namespace qnav;

static std::string make_tmp_dir()
{
    char tmpl[] = "/tmp/simevo-test-XXXXXX";
    assert_non_null(mkdtemp(tmpl));
    return tmpl;
}

static std::string slurp(const std::string &p)
{
    std::string s;
    assert_true(read_file(p, s));
    return s;
}

/* All regular files under dir, relative path -> content. */
static void collect(const std::string &dir, const std::string &rel, std::map<std::string, std::string> &out)
{
    DIR *d = opendir(join_path(dir, rel).c_str());
    assert_non_null(d);
    while (dirent *e = readdir(d)) {
        const std::string n = e->d_name;
        if (n == "." || n == "..") {
            continue;
        }
        const std::string r = rel.empty() ? n : rel + "/" + n;
        struct stat st;
        stat(join_path(dir, r).c_str(), &st);
        if (S_ISDIR(st.st_mode)) {
            collect(dir, r, out);
        } else {
            out[r] = slurp(join_path(dir, r));
        }
    }
    closedir(d);
}

static TaskDef fake_task(const std::string &dir)
{
    TaskDef t;
    t.dir = dir;
    t.label = "direct";
    t.episodes = 300;
    t.evolution.population = 8;
    t.evolution.hidden = 3;
    t.evolution_seed = 17;
    t.episode_seed_base = 23;
    t.eval_episodes = 12;
    t.eval_seed_base = 5;
    return t;
}

/* An observer that sets stop once n episodes have been reported (seen counts them). */
static TaskObserver stop_after(uint64_t n, uint64_t &seen, std::atomic<bool> &stop)
{
    TaskObserver obs;
    obs.episodes_done = [n, &seen, &stop](uint64_t more, bool) {
        seen += more;
        if (seen >= n) {
            stop = true;
        }
    };
    return obs;
}

static RunnerFactory fake_factory()
{
    return [](const Scenario &, uint64_t) -> std::unique_ptr<EpisodeRunner> { return std::make_unique<FakeRunner>(); };
}

/* Runs task t until `stop_at` episodes are reported (it must stop incomplete), appends
 * `torn` to its journal as a kill in the middle of a write leaves half a line, and resumes
 * it to the end. Returns the episodes replayed from the journal. */
static uint64_t stop_tear_and_resume(const TaskDef &t, uint64_t stop_at, const char *torn)
{
    std::atomic<bool> stop{false};
    uint64_t seen = 0;
    assert_false(run_task(t, "", fake_factory(), stop_after(stop_at, seen, stop), stop));
    assert_false(file_exists(join_path(t.dir, "done")));
    assert_false(file_exists(join_path(t.dir, "best.policy")));
    FILE *f = std::fopen(join_path(t.dir, "episodes.csv").c_str(), "a");
    std::fputs(torn, f);
    std::fclose(f);
    uint64_t replayed = 0;
    TaskObserver obs;
    obs.episodes_done = [&](uint64_t n, bool r) { replayed += r ? n : 0; };
    const std::atomic<bool> never{false};
    assert_true(run_task(t, "", fake_factory(), obs, never));
    return replayed;
}

static void test_task_stopped_and_resumed_matches_uninterrupted_bytes(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    TaskDef a = fake_task(join_path(root, "a"));
    assert_true(run_task(a, "", fake_factory(), TaskObserver{}, never));

    TaskDef b = fake_task(join_path(root, "b"));
    assert_int_equal(stop_tear_and_resume(b, 137, "137,-3.2500000"), 137); // from the journal, not re-simulated

    for (const char *name : {"episodes.csv", "best.policy", "eval.csv", "task.txt", "done"}) {
        assert_true(slurp(join_path(a.dir, name)) == slurp(join_path(b.dir, name)));
    }
    assert_int_equal(read_journal(join_path(b.dir, "episodes.csv")).R.size(), 300);
    assert_int_equal(read_eval(join_path(b.dir, "eval.csv")).size(), 12);
}

/* A FakeRunner that logs the seed of every episode it runs into a shared list. */
class SeedLoggingRunner : public FakeRunner {
public:
    explicit SeedLoggingRunner(std::vector<uint64_t> *log) : log_(log) {}
    EpisodeOutcome run(const qnav_policy_t &policy, uint64_t episode_seed) override
    {
        log_->push_back(episode_seed);
        return FakeRunner::run(policy, episode_seed);
    }

private:
    std::vector<uint64_t> *log_;
};

static void test_candidate_and_parent_face_the_same_k_episodes_and_the_budget_counts_episodes(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    TaskDef t = fake_task(join_path(root, "k3"));
    t.episodes = 60; // 20 steps of 3 episodes
    t.evolution.episodes_per_candidate = 3;
    t.eval_episodes = 0;
    std::vector<uint64_t> seeds;
    RunnerFactory make = [&seeds](const Scenario &, uint64_t) -> std::unique_ptr<EpisodeRunner> {
        return std::make_unique<SeedLoggingRunner>(&seeds);
    };
    assert_true(run_task(t, "", make, TaskObserver{}, never));
    assert_int_equal(read_journal(join_path(t.dir, "episodes.csv")).R.size(), 20);
    // 8 initial members on 3 episodes each, then 12 steps of candidate + parent.
    assert_int_equal(seeds.size(), 8 * 3 + 12 * 6);
    for (uint64_t step = 8; step < 20; ++step) {
        const std::size_t at = 8 * 3 + (step - 8) * 6;
        for (uint64_t j = 0; j < 3; ++j) {
            assert_true(seeds[at + j] == mix_seed(t.episode_seed_base, step * 3 + j)); // candidate
            assert_true(seeds[at + 3 + j] == seeds[at + j]);                          // parent: same
        }
    }
    assert_true(seeds[24] != seeds[30]); // the next step has new start points
}

/* The evolution strategy as a task: every step of an iteration faces the iteration's k
 * episodes, the budget rounds up to whole iterations, and a task stopped mid-iteration
 * (with half a journal line) resumes to the uninterrupted bytes. */
static void test_es_task_shares_worlds_per_iteration_and_resumes_to_identical_bytes(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    auto es_task = [&](const std::string &name) {
        TaskDef t = fake_task(join_path(root, name));
        t.evolution.algorithm = EvolutionParams::Algorithm::Es;
        t.evolution.es_pairs = 3; // 7 steps an iteration
        t.evolution.episodes_per_candidate = 2;
        t.episodes = 60; // 30 steps, rounded up to 5 iterations
        return t;
    };
    TaskDef a = es_task("a");
    std::vector<uint64_t> seeds;
    RunnerFactory logging = [&seeds](const Scenario &, uint64_t) -> std::unique_ptr<EpisodeRunner> {
        return std::make_unique<SeedLoggingRunner>(&seeds);
    };
    assert_true(run_task(a, "", logging, TaskObserver{}, never));
    assert_int_equal(read_journal(join_path(a.dir, "episodes.csv")).R.size(), 35);
    assert_true(seeds.size() >= 35 * 2);
    for (uint64_t step = 0; step < 35; ++step) {
        for (uint64_t j = 0; j < 2; ++j) {
            assert_true(seeds[step * 2 + j] == mix_seed(a.episode_seed_base, (step / 7) * 2 + j));
        }
    }
    assert_true(slurp(join_path(a.dir, "task.txt")).find(" algorithm=es es_pairs=3 ") != std::string::npos);

    TaskDef b = es_task("b");
    assert_int_equal(stop_tear_and_resume(b, 37, "19,-3.25"), 38); // 19 steps of 2, mid-iteration
    for (const char *name : {"episodes.csv", "best.policy", "eval.csv", "task.txt", "done"}) {
        assert_true(slurp(join_path(a.dir, name)) == slurp(join_path(b.dir, name)));
    }
}

static void test_checkpoints_resume_to_identical_bytes_even_when_a_row_is_missing(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    auto task = [&](const std::string &name) {
        TaskDef t = fake_task(join_path(root, name));
        t.episodes = 120;
        t.evolution.episodes_per_candidate = 2;
        t.checkpoints = {20, 50, 100};
        t.checkpoint_episodes = 4;
        return t;
    };
    const TaskDef a = task("a");
    assert_true(run_task(a, "", fake_factory(), TaskObserver{}, never));
    const auto rows = read_checkpoints(join_path(a.dir, "checkpoints.csv"));
    assert_int_equal(rows.size(), 3);
    assert_int_equal(rows[1].checkpoint, 50);
    assert_int_equal(rows[1].episodes, 50);
    assert_int_equal(rows[1].n, 4);

    const TaskDef b = task("b");
    std::atomic<bool> stop{false};
    uint64_t seen = 0;
    assert_false(run_task(b, "", fake_factory(), stop_after(70, seen, stop), stop));
    // Killed after the journal line of step 25 but before checkpoint 50 was written whole.
    const std::string ck = join_path(b.dir, "checkpoints.csv");
    std::string text = slurp(ck);
    assert_int_equal(std::count(text.begin(), text.end(), '\n'), 3); // header, 20, 50
    text = text.substr(0, text.rfind('\n', text.size() - 2) + 1) + "50,50,4,-1.2";
    write_file_atomic(ck, text);
    assert_true(run_task(b, "", fake_factory(), TaskObserver{}, never));
    for (const char *name : {"episodes.csv", "checkpoints.csv", "best.policy", "eval.csv", "task.txt"}) {
        assert_true(slurp(join_path(a.dir, name)) == slurp(join_path(b.dir, name)));
    }
}

static void test_transfer_task_resumes_from_source_file_and_refuses_other_settings(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    qnav_policy_t src;
    qnav_policy_net_zero(&src, 3);
    src.u.net.w_theta[0] = 512;
    char err[QNAV_POLICY_IO_ERRLEN];
    const std::string src_path = join_path(root, "src.policy");
    assert_int_equal(qnav_policy_write(src_path.c_str(), &src, "test source", err, sizeof err), 0);

    TaskDef a = fake_task(join_path(root, "a"));
    a.label = "transfer-x";
    assert_true(run_task(a, src_path, fake_factory(), TaskObserver{}, never));
    const std::string journal = slurp(join_path(a.dir, "episodes.csv"));
    // Same folder, other seed: refused with the settings file named.
    TaskDef other = a;
    other.evolution_seed = 18;
    try {
        run_task(other, src_path, fake_factory(), TaskObserver{}, never);
        fail();
    } catch (const UserError &e) {
        assert_non_null(std::strstr(e.what(), "task.txt: this output folder was made with different settings"));
    }
    // A probabilistic policy cannot seed a network population.
    qnav_policy_t prob;
    qnav_policy_prob_default(&prob);
    const std::string prob_path = join_path(root, "prob.policy");
    assert_int_equal(qnav_policy_write(prob_path.c_str(), &prob, nullptr, err, sizeof err), 0);
    TaskDef c = fake_task(join_path(root, "c"));
    try {
        run_task(c, prob_path, fake_factory(), TaskObserver{}, never);
        fail();
    } catch (const UserError &e) {
        assert_non_null(std::strstr(e.what(), "incompatible policy"));
    }
    assert_true(journal == slurp(join_path(a.dir, "episodes.csv")));
}

// Three runs of two sources and a target, small enough to run in a test.
static ExperimentSpec fake_experiment()
{
    return parse_experiment(R"(name = "fake"
runs = 3
curve_bin = 20
[evolution]
population = 6
hidden = 3
[target]
episodes = 100
[[source]]
label = "a"
episodes = 60
[[source]]
label = "b"
episodes = 80
[evaluation]
episodes = 7
checkpoints = [20, 50, 500]
checkpoint_every = 0
checkpoint_episodes = 3
arrival_threshold = 50
)", "fake.toml");
}

// The summary's "direct" row is what the run directories under root hold.
static void check_direct_summary_reads_the_runs(const std::string &root, const ConditionSummary &direct)
{
    assert_string_equal(direct.label.c_str(), "direct");
    assert_int_equal(direct.final_per_run.size(), 3);
    assert_int_equal(direct.curve_mean.size(), 5);
    std::vector<double> r;
    for (const auto &o : read_eval(join_path(root, "one/run-002/direct/eval.csv"))) {
        r.push_back(o.R);
    }
    assert_true(std::fabs(direct.final_per_run[1] - mean_of(r)) < 1e-12);
    // What the robots do: arrival and recovery ticks per run, held out and at checkpoints.
    double arrived = 0, tau = 0;
    for (const auto &o : read_eval(join_path(root, "one/run-002/direct/eval.csv"))) {
        arrived += o.reached ? 1 : 0;
        tau += o.tau_c;
    }
    assert_true(std::fabs(direct.arrival_per_run[1] - arrived / 7) < 1e-12);
    assert_true(std::fabs(direct.tau_c_per_run[1] - tau / 7) < 1e-12);
    assert_true(direct.arrival.lo <= direct.arrival.mean && direct.arrival.mean <= direct.arrival.hi);
    assert_int_equal(direct.checkpoints.size(), 2); // 500 is beyond the budget: dropped
    const auto rows = read_checkpoints(join_path(root, "one/run-003/direct/checkpoints.csv"));
    assert_true(std::fabs(direct.checkpoints[1].arrival[2] - rows[1].arrived / 3.0) < 1e-12);
    assert_int_equal(direct.to_threshold.size(), 3);
    uint32_t not_reached = 0;
    for (double x : direct.to_threshold) {
        not_reached += std::isnan(x) ? 1 : 0;
        assert_true(std::isnan(x) || x == 20 || x == 50);
    }
    assert_int_equal(direct.threshold_not_reached, not_reached);
}

static void test_experiment_results_do_not_depend_on_thread_count_and_summary_reads_them(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    ExperimentSpec spec = fake_experiment();
    const auto t1 = plan_tasks(spec, join_path(root, "one"));
    const auto t3 = plan_tasks(spec, join_path(root, "three"));
    // 3 runs x (2 sources + 2 transfers + direct) + probabilistic
    assert_int_equal(t1.size(), 16);
    for (const TaskDef &t : t1) {
        if (t.label.rfind("transfer-", 0) == 0) {
            assert_true(t.source_task >= 0);
            assert_true(t1[static_cast<size_t>(t.source_task)].label == "source-" + t.label.substr(9));
        }
    }
    run_tasks(t1, fake_factory(), 1, false, "one");
    run_tasks(t3, fake_factory(), 3, false, "three");
    std::map<std::string, std::string> f1, f3;
    collect(join_path(root, "one"), "", f1);
    collect(join_path(root, "three"), "", f3);
    assert_true(f1 == f3);

    const ExperimentSummary S = summarize(spec, t1);
    assert_int_equal(S.conditions.size(), 5); // transfer-a, transfer-b, direct, probabilistic, vfh
    assert_int_equal(S.comparisons.size(), 8); // 2 vs direct, 3 vs each reference
    assert_string_equal(S.conditions[4].label.c_str(), "vfh");
    assert_int_equal(S.conditions[4].final_per_run.size(), 7); // VFH+: per episode, same held-out set
    assert_true(std::fabs(S.conditions[4].final_mean - S.conditions[3].final_mean) > 1.0); // its own episodes
    assert_int_equal(S.conditions[3].final_per_run.size(), 7); // probabilistic: per episode
    const ConditionSummary &direct = S.conditions[2];
    check_direct_summary_reads_the_runs(root, direct);
    assert_int_equal(S.conditions[0].checkpoints[0].R.size(), 3); // transfer-a: one value per run
    assert_true(S.comparisons[0].a == "transfer-a" && S.comparisons[0].b == "direct");
    assert_true(std::fabs(S.comparisons[0].difference - (S.conditions[0].final_mean - direct.final_mean)) < 1e-12);
}

/* Run simevo with args; returns exit status; stderr captured to err_path. */
static pid_t spawn(const std::vector<std::string> &args, const std::string &err_path)
{
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        const int fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 2);
        const int nul = open("/dev/null", O_WRONLY);
        dup2(nul, 1);
        std::vector<char *> argv;
        argv.push_back(const_cast<char *>(SIMEVO_EXE));
        for (const auto &a : args) {
            argv.push_back(const_cast<char *>(a.c_str()));
        }
        argv.push_back(nullptr);
        setenv("QNAV_DATA_DIR", SIMEVO_SOURCE_DIR "/data", 1);
        execv(SIMEVO_EXE, argv.data());
        _exit(127);
    }
    return pid;
}

/* spawn with stdout to out_path as well. */
static pid_t spawn_out(const std::vector<std::string> &args, const std::string &err_path, const std::string &out_path)
{
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        const int fd = open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 1);
        std::vector<std::string> a = args;
        const int efd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(efd, 2);
        std::vector<char *> argv;
        argv.push_back(const_cast<char *>(SIMEVO_EXE));
        for (const auto &x : a) {
            argv.push_back(const_cast<char *>(x.c_str()));
        }
        argv.push_back(nullptr);
        setenv("QNAV_DATA_DIR", SIMEVO_SOURCE_DIR "/data", 1);
        execv(SIMEVO_EXE, argv.data());
        _exit(127);
    }
    return pid;
}

static int wait_exit(pid_t pid)
{
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

static int count_lines(const std::string &path)
{
    std::string s;
    if (!read_file(path, s)) {
        return 0;
    }
    int n = 0;
    for (char c : s) {
        n += c == '\n';
    }
    return n;
}

/* Every file under a and b is the same (same names, same bytes); a holds a summary. */
static void assert_same_files(const std::string &a, const std::string &b)
{
    std::map<std::string, std::string> fa, fb;
    collect(a, "", fa);
    collect(b, "", fb);
    assert_int_equal(fa.size(), fb.size());
    for (auto &kv : fa) {
        assert_true(fb.count(kv.first) == 1);
        if (kv.second != fb[kv.first]) {
            print_error("differs: %s\n", kv.first.c_str());
            fail();
        }
    }
    assert_true(fa.count("tiny/summary.md") == 1);
    assert_true(fa["tiny/STATUS"] == "complete\n");
}

static void test_shares_in_separate_processes_merge_to_the_local_run_byte_for_byte(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string a = join_path(root, "a"), b = join_path(root, "b"), c = join_path(root, "c");
    auto run = [&](const std::string &out, std::vector<std::string> extra) {
        std::vector<std::string> v = {"run", SIMEVO_TEST_DIR "/tiny.toml", "--no-plot", "--no-progress", "-j", "1", "--out", out};
        v.insert(v.end(), extra.begin(), extra.end());
        return v;
    };
    auto summarize = [&](const std::string &out) {
        return std::vector<std::string>{"summarize", join_path(out, "tiny"), "--no-plot"};
    };
    assert_int_equal(wait_exit(spawn(run(a, {}), join_path(root, "a.err"))), 0);
    // The summary's Regenerate line, run as written (with the same --out), finds every task
    // done and rewrites the same files (issue 20: it named 'tiny', which no folder holds).
    {
        const std::string summary = slurp(join_path(a, "tiny/summary.md"));
        const std::size_t at = summary.find("Regenerate: `simevo run ");
        assert_true(at != std::string::npos);
        const std::size_t from = at + std::strlen("Regenerate: `simevo "), to = summary.find('`', from);
        std::vector<std::string> regen;
        const std::string line = summary.substr(from, to - from) + " ";
        for (std::size_t i = 0, sp; (sp = line.find(' ', i)) != std::string::npos; i = sp + 1) {
            regen.push_back(line.substr(i, sp - i));
        }
        assert_string_equal(regen[1].c_str(), SIMEVO_TEST_DIR "/tiny.toml");
        std::map<std::string, std::string> before, after;
        collect(a, "", before);
        regen.insert(regen.end(), {"--no-plot", "--no-progress", "--out", a});
        assert_int_equal(wait_exit(spawn(regen, join_path(root, "regen.err"))), 0);
        collect(a, "", after);
        assert_true(before == after);
    }

    // Three shares one after another; summarize refuses until all are done.
    assert_int_equal(wait_exit(spawn(run(b, {"--tasks", "1/3"}), join_path(root, "b1.err"))), 0);
    assert_int_equal(wait_exit(spawn(run(b, {"--tasks", "2/3"}), join_path(root, "b2.err"))), 0);
    assert_false(file_exists(join_path(b, "tiny/summary.md")));
    assert_int_equal(wait_exit(spawn(summarize(b), join_path(root, "bs.err"))), 1);
    const std::string missing = slurp(join_path(root, "bs.err"));
    assert_non_null(std::strstr(missing.c_str(), "tiny/probabilistic: not started"));
    assert_non_null(std::strstr(missing.c_str(), "3 of 7 tasks not finished; no summary written"));
    assert_false(file_exists(join_path(b, "tiny/summary.md")));
    assert_int_equal(wait_exit(spawn(run(b, {"--tasks", "3/3"}), join_path(root, "b3.err"))), 0);
    assert_int_equal(wait_exit(spawn(summarize(b), join_path(root, "bs2.err"))), 0);
    assert_same_files(a, b);

    // Stage 2 before its sources says so; two stage-1 processes at once do not conflict.
    assert_int_equal(wait_exit(spawn(run(c, {"--stage", "2"}), join_path(root, "c0.err"))), 1);
    assert_non_null(std::strstr(slurp(join_path(root, "c0.err")).c_str(),
                                "tiny/run-001/transfer-open: its source task"));
    const pid_t p1 = spawn(run(c, {"--stage", "1", "--tasks", "1/2"}), join_path(root, "c1.err"));
    const pid_t p2 = spawn(run(c, {"--stage", "1", "--tasks", "2/2"}), join_path(root, "c2.err"));
    assert_int_equal(wait_exit(p1), 0);
    assert_int_equal(wait_exit(p2), 0);
    assert_int_equal(wait_exit(spawn(run(c, {"--stage", "2"}), join_path(root, "c3.err"))), 0);
    assert_int_equal(wait_exit(spawn(summarize(c), join_path(root, "cs.err"))), 0);
    assert_same_files(a, c);

    // A share of another preset is refused: the folder holds other settings.
    assert_int_equal(wait_exit(spawn(run(c, {"--tasks", "1/2", "--runs", "3"}), join_path(root, "c4.err"))), 1);
    assert_non_null(std::strstr(slurp(join_path(root, "c4.err")).c_str(), "settings.txt: this output folder holds tiny with other settings"));
}

static void test_slurm_scripts_run_stage_two_after_stage_one_and_keep_foreign_files(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::vector<std::string> args = {"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--out", root, "--array-limit", "3",
                                           "--tasks-per-job", "2", "--partition", "debug", "--time", "5"};
    assert_int_equal(wait_exit(spawn(args, join_path(root, "s.err"))), 0);
    const std::string submit = slurp(join_path(root, "tiny/slurm/submit.sh"));
    // 5 stage-1 tasks in 3 array tasks, 2 transfers in 1, after stage 1 succeeded
    assert_non_null(std::strstr(submit.c_str(), "sbatch --parsable --array=1-3%3 tasks.sbatch 1 3)\n"));
    assert_non_null(std::strstr(submit.c_str(),
                                "--array=1-1%3 --dependency=afterok:$a --kill-on-invalid-dep=yes tasks.sbatch 2 1)\n"));
    assert_non_null(std::strstr(submit.c_str(), "--dependency=afterany:$after summarize.sbatch"));
    const std::string tasks = slurp(join_path(root, "tiny/slurm/tasks.sbatch"));
    assert_non_null(std::strstr(tasks.c_str(), "#SBATCH --partition=debug\n#SBATCH --time=5\n"));
    assert_non_null(std::strstr(tasks.c_str(), "--stage \"$1\" --tasks \"$SLURM_ARRAY_TASK_ID/$2\"\n"));
    assert_true(file_exists(join_path(root, "tiny/run.txt")));
    // A file in slurm/ that simevo did not write is left alone.
    write_file_atomic(join_path(root, "tiny/slurm/summarize.sbatch"), "#!/bin/sh\necho mine\n");
    assert_int_equal(wait_exit(spawn(args, join_path(root, "s2.err"))), 1);
    assert_non_null(std::strstr(slurp(join_path(root, "s2.err")).c_str(), "exists and was not written by simevo slurm"));
    assert_true(slurp(join_path(root, "tiny/slurm/summarize.sbatch")) == "#!/bin/sh\necho mine\n");
}

static void test_program_killed_by_pid_resumes_to_identical_results(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string spec = SIMEVO_TEST_DIR "/tiny.toml";
    const std::vector<std::string> common = {"run", spec, "--no-plot", "--no-progress", "-j", "1"};
    auto with_out = [&](const std::string &out) {
        auto v = common;
        v.push_back("--out");
        v.push_back(out);
        return v;
    };
    const std::string a = join_path(root, "a");
    const std::string b = join_path(root, "b");
    assert_int_equal(wait_exit(spawn(with_out(a), join_path(root, "a.err"))), 0);

    // Kill b once the first run's direct evolution is part-way through.
    const pid_t pid = spawn(with_out(b), join_path(root, "b.err"));
    const std::string watch = join_path(b, "tiny/run-001/direct/episodes.csv");
    bool killed = false;
    for (int i = 0; i < 150000 && !killed; ++i) { // 300 s: only ends a broken run
        if (count_lines(watch) >= 15) {
            kill(pid, SIGKILL);
            killed = true;
        } else {
            usleep(2000);
        }
    }
    assert_true(killed);
    assert_int_equal(wait_exit(pid), 128 + SIGKILL);
    assert_false(file_exists(join_path(b, "tiny/summary.md")));
    assert_true(slurp(join_path(b, "tiny/STATUS")).rfind("incomplete", 0) == 0);
    // Really in the middle: later tasks have not finished.
    assert_false(file_exists(join_path(b, "tiny/run-002/direct/done")));
    assert_false(file_exists(join_path(b, "tiny/probabilistic/done")));

    assert_int_equal(wait_exit(spawn(with_out(b), join_path(root, "b2.err"))), 0);
    assert_same_files(a, b);

    // While another process holds a task's lock, simevo refuses to run that task.
    const int lfd = open(join_path(a, "tiny/run-001/source-open/.lock").c_str(), O_RDWR);
    assert_true(lfd >= 0 && flock(lfd, LOCK_EX | LOCK_NB) == 0);
    assert_int_equal(wait_exit(spawn(with_out(a), join_path(root, "lock.err"))), 1);
    assert_non_null(std::strstr(slurp(join_path(root, "lock.err")).c_str(), "run-001/source-open: another simevo is running this task"));
    close(lfd);

    // The same folder with other settings is refused and left as it was.
    auto other = with_out(a);
    other.insert(other.end(), {"--runs", "3"});
    const std::string err_path = join_path(root, "c.err");
    assert_int_equal(wait_exit(spawn(other, err_path)), 1);
    const std::string err = slurp(err_path);
    assert_non_null(std::strstr(err.c_str(), "settings.txt: this output folder holds tiny with other settings"));
    assert_true(err.find('\n') == err.size() - 1);
    assert_true(slurp(join_path(a, "tiny/STATUS")) == "complete\n");
}

static void test_table_mode_and_network_mode_give_identical_results(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::vector<std::string> base = {"run", SIMEVO_TEST_DIR "/tiny.toml", "--no-plot", "--no-progress",
                                           "--runs", "1", "-j", "2"};
    auto args = base;
    args.insert(args.end(), {"--out", join_path(root, "table")});
    assert_int_equal(wait_exit(spawn(args, join_path(root, "t.err"))), 0);
    args = base;
    args.insert(args.end(), {"--out", join_path(root, "network"), "--network-mode"});
    assert_int_equal(wait_exit(spawn(args, join_path(root, "n.err"))), 0);
    std::map<std::string, std::string> ft, fn;
    collect(join_path(root, "table"), "", ft);
    collect(join_path(root, "network"), "", fn);
    assert_true(ft.size() > 10);
    assert_true(ft == fn);
}

/* `simevo run generalist --preset quick`, shrunk: it writes recommended.policy (a copy of
 * one run's best policy, the one its summary names, or the robot's probabilistic policy
 * when no run was ahead of it on the validation worlds), and prints its test arrival in
 * every world family and every named environment, one line each with recovery ticks. */
static void test_generalist_quick_run_writes_the_recommended_policy_and_its_test_lines(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string out = join_path(root, "out.txt");
    const std::vector<std::string> args = {"run", SIMEVO_SOURCE_DIR "/experiments/generalist.toml", "--preset", "quick",
                                           "--runs", "1", "--episodes", "48", "--source-episodes", "24",
                                           "--eval-episodes", "4", "--no-plot", "--no-progress", "-j", "2",
                                           "--out", root};
    assert_int_equal(wait_exit(spawn_out(args, join_path(root, "err"), out)), 0);
    const std::string dir = join_path(root, "generalist");
    const std::string rec = slurp(join_path(dir, "recommended.policy"));
    const std::string json = slurp(join_path(dir, "summary.json"));
    const std::size_t at = json.find("\"recommended\": {\"condition\": \"");
    assert_true(at != std::string::npos);
    const std::size_t c0 = at + std::strlen("\"recommended\": {\"condition\": \"");
    const std::string condition = json.substr(c0, json.find('"', c0) - c0);
    const std::string text = slurp(out);
    assert_non_null(std::strstr(text.c_str(), "generalist: recommended policy "));
    if (condition == "probabilistic") {
        assert_non_null(std::strstr(rec.c_str(), "\nkind probabilistic\n"));
        assert_non_null(std::strstr(text.c_str(), "(the probabilistic policy: no evolved run was ahead of it"));
    } else {
        assert_true(condition == "direct" || condition == "transfer-easy");
        assert_true(rec == slurp(join_path(join_path(join_path(dir, "run-001"), condition), "best.policy")));
        assert_non_null(std::strstr(text.c_str(), "without touching anything, R "));
        assert_non_null(std::strstr(text.c_str(), "; the probabilistic policy "));
    }
    for (const char *w : {"family clutter:", "family gaps:", "family corridor:", "family pocket:", "family rooms:",
                          "environment cluttered:", "environment dense:", "environment open:", "environment single:"}) {
        const std::size_t line = text.find(std::string("generalist: test ") + w);
        assert_true(line != std::string::npos);
        assert_true(text.find("recovery ticks", line) < text.find('\n', line));
    }
    assert_non_null(std::strstr(slurp(join_path(dir, "summary.md")).c_str(), "## Recommended policy"));
}

static std::string run_for_error(const std::vector<std::string> &args, int &status)
{
    const std::string root = make_tmp_dir();
    const std::string err = join_path(root, "err");
    status = wait_exit(spawn(args, err));
    return slurp(err);
}

static void assert_one_line_containing(const std::string &text, const char *needle)
{
    assert_non_null(std::strstr(text.c_str(), needle));
    assert_true(!text.empty() && text.back() == '\n');
    assert_true(text.find('\n') == text.size() - 1); // exactly one line
}

static void test_program_rejects_bad_input_with_one_line(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    int st = 0;
    std::string e = run_for_error({"run", "no-such-experiment", "--out", root}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "unknown experiment 'no-such-experiment'");

    const std::string bad = join_path(root, "bad.toml");
    write_file_atomic(bad, "name = \"bad\"\n[target]\nsectors = 32\nspeed = 3\n");
    e = run_for_error({"run", bad, "--out", root}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, (bad + ":4: unknown key 'speed' in [target]").c_str());

    const std::string missing = join_path(root, "missing.toml");
    write_file_atomic(missing, "name = \"missing\"\n[target]\nepisodes = 5\n[[source]]\nlabel = \"f\"\npolicy = \"" +
                                   root + "/nope.policy\"\n");
    e = run_for_error({"run", missing, "--out", root, "--no-plot"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "nope.policy: policy file not found");
    assert_false(file_exists(join_path(root, "missing/summary.md")));

    qnav_policy_t prob;
    qnav_policy_prob_default(&prob);
    char err[QNAV_POLICY_IO_ERRLEN];
    assert_int_equal(qnav_policy_write(join_path(root, "prob.policy").c_str(), &prob, nullptr, err, sizeof err), 0);
    const std::string incompatible = join_path(root, "incompatible.toml");
    write_file_atomic(incompatible, "name = \"inc\"\n[target]\nepisodes = 5\n[[source]]\nlabel = \"f\"\npolicy = \"" +
                                        root + "/prob.policy\"\n");
    e = run_for_error({"run", incompatible, "--out", root, "--no-plot"}, st);
    assert_int_equal(st, 1); /* found once the run has started */
    assert_one_line_containing(e, "incompatible policy");
    assert_false(file_exists(join_path(root, "inc/summary.md")));

    e = run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--preset", "nope", "--out", root}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "no preset 'nope'");
}

/* A `fit` source: the run writes the network fitted to the target robot's probabilistic
 * policy into the experiment's folder, the transfer starts from it, the summary names it,
 * and a rerun finds the same file. `simevo fit` writes one and never overwrites a file. */
static void test_fit_source_is_written_once_and_transfers_start_from_it(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string spec = join_path(root, "fitted.toml");
    write_file_atomic(spec, "name = \"fitted\"\nruns = 1\nseed = 5\ncurve_bin = 10\n[evolution]\npopulation = 6\n"
                            "hidden = 2\n[target]\nenvironment = \"dense\"\nrobot = \"tekbot\"\nsectors = 16\n"
                            "episodes = 20\nepisode_limit_s = 15\n[[source]]\nlabel = \"prob\"\n"
                            "fit = \"probabilistic\"\n[evaluation]\nepisodes = 2\nworlds_episodes = 1\n");
    for (int pass = 0; pass < 2; ++pass) {
        assert_int_equal(wait_exit(spawn({"run", spec, "--out", root, "--no-plot"}, join_path(root, "run.err"))), 0);
    }
    qnav_policy_t fitted;
    char err[QNAV_POLICY_IO_ERRLEN];
    assert_int_equal(qnav_policy_read(join_path(root, "fitted/source-prob.policy").c_str(), &fitted, err, sizeof err), 0);
    assert_int_equal(fitted.kind, QNAV_POLICY_NET);
    assert_int_equal(fitted.u.net.hidden, 2);
    assert_non_null(std::strstr(slurp(join_path(root, "fitted/settings.txt")).c_str(), "\nsource=source-prob.policy\n"));
    assert_non_null(std::strstr(slurp(join_path(root, "fitted/summary.md")).c_str(),
                                "the network fitted to the target robot's probabilistic policy"));

    const std::string out = join_path(root, "fit.policy");
    assert_int_equal(wait_exit(spawn({"fit", "--robot", "tekbot", "--hidden", "2", "--starts", "1", "--iterations", "50",
                                      "--out", out},
                                     join_path(root, "fit.err"))),
                     0);
    assert_int_equal(qnav_policy_read(out.c_str(), &fitted, err, sizeof err), 0);
    int st = 0;
    const std::string e = run_for_error({"fit", "--out", out}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, (out + ": exists; not overwritten").c_str());
}

/* Issue 20: a value that ends an #SBATCH line (a newline in --partition, --time or the
 * output folder) became a shell command in tasks.sbatch; each is refused with one line
 * before any file is written, and a folder with a space or '#' is quoted in --output. */
static void test_slurm_refuses_values_that_would_break_an_sbatch_line(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string out = join_path(root, "out");
    int st = 0;
    std::string e = run_for_error({"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--out", out, "--partition", "p\ntouch X"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--partition: 'p\\ntouch X' is not a Slurm partition name");
    e = run_for_error({"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--out", out, "--time", "5\ntouch X"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--time: '5\\ntouch X' is not a Slurm time limit");
    e = run_for_error({"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--out", out + "\ntouch X"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "cannot go on an #SBATCH line");
    assert_false(file_exists(out));
    assert_false(file_exists(out + "\ntouch X"));

    const std::string odd = join_path(root, "a b#c%d");
    assert_int_equal(wait_exit(spawn({"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--out", odd, "--partition", "debug,long",
                                      "--time", "1-02:30:00"},
                                     join_path(root, "ok.err"))),
                     0);
    const std::string tasks = slurp(join_path(odd, "tiny/slurm/tasks.sbatch"));
    assert_non_null(std::strstr(tasks.c_str(), "#SBATCH --partition=debug,long\n#SBATCH --time=1-02:30:00\n"));
    assert_non_null(std::strstr(tasks.c_str(), ("#SBATCH --output=\"" + root + "/a b#c%%d/tiny/slurm/%x-%A_%a.out\"\n").c_str()));
}

/* The temporary name write_file_atomic used before it made them with mkstemp: a planted
 * symlink there was followed and the file it pointed to overwritten. */
static void test_atomic_write_never_follows_a_planted_symlink(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir(), outside = make_tmp_dir();
    const std::string victim = join_path(outside, "victim.txt"), target = join_path(root, "summary.md");
    write_file_atomic(victim, "keep me\n");
    const std::string old_tmp = target + ".tmp" + std::to_string(::getpid()) + "-" +
                                std::to_string(std::hash<std::thread::id>()(std::this_thread::get_id()) % 100000);
    assert_int_equal(symlink(victim.c_str(), old_tmp.c_str()), 0);
    write_file_atomic(target, "new content\n");
    assert_string_equal(slurp(victim).c_str(), "keep me\n");
    assert_string_equal(slurp(target).c_str(), "new content\n");
    std::map<std::string, std::string> files;
    collect(root, "", files);
    assert_int_equal(files.size(), 2); /* the target and the planted link: no temporary left */
    struct stat st;
    assert_int_equal(stat(target.c_str(), &st), 0);
    assert_int_equal(st.st_mode & 0777, 0644);
}

static bool process_gone(pid_t pid)
{
    char path[64], text[512] = "";
    std::snprintf(path, sizeof path, "/proc/%d/stat", static_cast<int>(pid));
    FILE *f = std::fopen(path, "r");
    if (f == nullptr) {
        return true;
    }
    const size_t n = std::fread(text, 1, sizeof text - 1, f);
    std::fclose(f);
    text[n] = '\0';
    const char *paren = std::strrchr(text, ')');
    return paren != nullptr && paren[1] == ' ' && (paren[2] == 'Z' || paren[2] == 'X');
}

/* simevo killed with SIGKILL while a plot script runs: the script dies too, instead of
 * living on to race the resumed run for the plot files. */
static void test_plot_child_dies_when_simevo_is_killed(void **state)
{
    (void)state;
    const std::string dir = make_tmp_dir();
    write_file_atomic(join_path(dir, "slow_plot.sh"),
                      "echo $$ > \"$1/pid.tmp\" && mv \"$1/pid.tmp\" \"$1/pid\" && exec sleep 120\n");
    const pid_t sim = fork();
    assert_true(sim >= 0);
    if (sim == 0) {
        RunOptions opt;
        opt.python = "/bin/sh";
        opt.tools_dir = dir;
        try {
            run_plot(opt, "slow_plot.sh", dir);
        } catch (...) {
        }
        _exit(0);
    }
    std::string text;
    for (int waited = 0; !read_file(join_path(dir, "pid"), text); waited += 20) {
        assert_true(waited < 300000);
        usleep(20000);
    }
    const pid_t plot = static_cast<pid_t>(std::atol(text.c_str()));
    assert_true(plot > 0);
    assert_false(process_gone(plot));
    assert_int_equal(kill(sim, SIGKILL), 0);
    assert_int_equal(wait_exit(sim), 128 + SIGKILL);
    int waited = 0;
    while (!process_gone(plot) && waited < 120000) {
        usleep(20000);
        waited += 20;
    }
    if (!process_gone(plot)) {
        kill(plot, SIGKILL);
        fail_msg("the plot script (pid %d) outlived simevo", static_cast<int>(plot));
    }
}

static std::string run_for_stdout(const std::string &args, int &status)
{
    const std::string cmd = std::string(SIMEVO_EXE) + " " + args + " 2>/dev/null";
    FILE *p = popen(cmd.c_str(), "r");
    assert_non_null(p);
    std::string out;
    char buf[512];
    while (fgets(buf, sizeof buf, p)) {
        out += buf;
    }
    const int st = pclose(p);
    status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return out;
}

static void test_program_command_line_names_unknown_options_and_subcommands(void **state)
{
    (void)state;
    int st = 0;
    std::string e = run_for_error({"--bogus"}, st);
    assert_int_equal(st, 2);
    assert_string_equal(e.c_str(), "simevo: --bogus: unknown option (see simevo --help)\n");
    e = run_for_error({"bogus"}, st);
    assert_int_equal(st, 2);
    assert_string_equal(e.c_str(),
                        "simevo: bogus: unknown subcommand (known: run, summarize, slurm, list, evolve, eval, quality, fit) (see simevo --help)\n");
    e = run_for_error({"eval", "prob", "--bogus"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--bogus");
    const std::string v = run_for_stdout("--version", st);
    assert_int_equal(st, 0);
    assert_string_equal(v.c_str(), "simevo (qnav) " QNAV_VERSION "\n");
}

/* Zero episodes, NaN or out-of-range noise: refused as bad usage, naming the option. */
static void test_program_refuses_zero_episodes_and_impossible_noise(void **state)
{
    (void)state;
    int st = 0;
    std::string e = run_for_error({"eval", "prob", "--episodes", "0"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--episodes");
    e = run_for_error({"evolve", "--eval-episodes", "0", "--out", make_tmp_dir() + "/never"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--eval-episodes");
    e = run_for_error({"evolve", "--noise", "nan"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "expected a number in [0, 1], got 'nan'");
    e = run_for_error({"evolve", "--sensor-noise", "5"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--sensor-noise");
    e = run_for_error({"eval", "prob", "--noise", "nan"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, "--noise");
}

/* Experiment files: noise above the simulator's 1 refused at its line before any output
 * is written; a directory named as the file; a quoted key with a newline on one line. */
static void test_experiment_file_problems_are_found_before_any_output(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string out = join_path(root, "out");
    const std::string noisy = join_path(root, "noisy.toml");
    write_file_atomic(noisy, "name = \"noisy\"\n[target]\nepisodes = 5\nnoise = 5\n");
    int st = 0;
    std::string e = run_for_error({"run", noisy, "--out", out, "--no-plot"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, (noisy + ":4: noise: 5 is outside [0, 1]").c_str());
    assert_false(file_exists(out));

    e = run_for_error({"run", root, "--out", out, "--no-plot"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, (root + ": is a directory, not a file").c_str());

    const std::string nl = join_path(root, "nl.toml");
    write_file_atomic(nl, "name = \"nl\"\n[target]\n\"a\\nb\" = 1\n");
    e = run_for_error({"run", nl, "--out", out, "--no-plot"}, st);
    assert_int_equal(st, 2);
    assert_one_line_containing(e, (nl + ":3: unknown key 'a\\nb' in [target]").c_str());
    assert_false(file_exists(out));
}

/* Every file under dir, by path relative to it; dir holds a finished experiment. */
static std::map<std::string, std::string> finished_files(const std::string &dir)
{
    std::map<std::string, std::string> f;
    collect(dir, "", f);
    assert_true(f.count("summary.md") == 1);
    assert_true(f["STATUS"] == "complete\n");
    return f;
}

/* A sweep of tiny over two noise levels, at path (members tiny.noise-0, tiny.noise-0.05). */
static void write_noise_sweep(const std::string &path)
{
    write_file_atomic(path, "name = \"tiny-noise\"\nexperiment = \"" SIMEVO_TEST_DIR "/tiny.toml\"\n"
                            "[vary]\nnoise = [0, 0.05]\n");
}

static void test_sweep_shares_merge_to_the_member_experiment_run_directly_with_its_variation(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string sweep = join_path(root, "sweep.toml"), a = join_path(root, "a"), b = join_path(root, "b");
    write_noise_sweep(sweep);
    auto run = [&](const std::string &file, const std::string &out, std::vector<std::string> extra) {
        std::vector<std::string> v = {"run", file, "--no-plot", "--no-progress", "-j", "1", "--out", out};
        v.insert(v.end(), extra.begin(), extra.end());
        return v;
    };
    const std::vector<std::string> summarize = {"summarize", join_path(b, "tiny-noise"), "--no-plot"};
    assert_int_equal(wait_exit(spawn(run(SIMEVO_TEST_DIR "/tiny.toml", a, {"--vary", "noise=0.05"}), join_path(root, "a.err"))), 0);

    // The sweep's shares (each share of every member), then the sweep-level merge.
    assert_int_equal(wait_exit(spawn(run(sweep, b, {"--stage", "1", "--tasks", "1/2"}), join_path(root, "b1.err"))), 0);
    assert_int_equal(wait_exit(spawn(run(sweep, b, {"--stage", "1", "--tasks", "2/2"}), join_path(root, "b2.err"))), 0);
    assert_int_equal(wait_exit(spawn(summarize, join_path(root, "bs.err"))), 1);
    const std::string missing = slurp(join_path(root, "bs.err"));
    assert_non_null(std::strstr(missing.c_str(), "tiny.noise-0/run-002/transfer-open: not started"));
    assert_non_null(std::strstr(missing.c_str(), "tiny.noise-0.05/run-001/transfer-open: not started"));
    assert_non_null(std::strstr(missing.c_str(), "tiny-noise: 2 of 2 experiments not finished"));
    assert_int_equal(wait_exit(spawn(run(sweep, b, {"--stage", "2"}), join_path(root, "b3.err"))), 0);
    assert_int_equal(wait_exit(spawn(summarize, join_path(root, "bs2.err"))), 0);

    const auto direct = finished_files(join_path(a, "tiny.noise-0.05"));
    assert_true(direct == finished_files(join_path(b, "tiny.noise-0.05")));
    assert_true(slurp(join_path(b, "tiny-noise/sweep.txt")).find("member = tiny.noise-0\nmember = tiny.noise-0.05\n") !=
                std::string::npos);
    // The variation is the target's noise only; the open source keeps the file's 0.
    const std::string settings = direct.at("settings.txt");
    assert_non_null(std::strstr(settings.c_str(), "environment=dense robot=tekbot sectors=16 sensor_noise=0.050000000000000003 actuation_noise=0.050000000000000003"));
    assert_non_null(std::strstr(settings.c_str(), "environment=open robot=tekbot sectors=16 sensor_noise=0 actuation_noise=0 "));
    assert_true(finished_files(join_path(b, "tiny.noise-0")).at("settings.txt") != settings);

    // A member folder alone merges again from its run.txt (the variation recorded there).
    assert_non_null(std::strstr(direct.at("run.txt").c_str(), "\nvary = noise=0.05\n"));
    assert_int_equal(wait_exit(spawn({"summarize", join_path(b, "tiny.noise-0.05"), "--no-plot"}, join_path(root, "m.err"))), 0);
    assert_true(direct == finished_files(join_path(b, "tiny.noise-0.05")));
}

static void test_slurm_sweep_writes_each_members_scripts_and_one_submit_for_all(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string out = join_path(root, "out"), sweep = join_path(root, "pair.toml");
    std::string tiny = slurp(SIMEVO_TEST_DIR "/tiny.toml");
    tiny.replace(tiny.find("name = \"tiny\""), 13, "name = \"tiny2\"");
    write_file_atomic(join_path(root, "tiny2.toml"), tiny);
    // a path relative to the sweep file's folder, and an absolute one
    write_file_atomic(sweep, "name = \"pair\"\nexperiments = [\"tiny2.toml\", \"" SIMEVO_TEST_DIR "/tiny.toml\"]\n");
    assert_int_equal(wait_exit(spawn({"slurm", sweep, "--out", out, "--runs", "3"}, join_path(root, "s.err"))), 0);
    const std::string submit = slurp(join_path(out, "pair/slurm/submit.sh"));
    assert_non_null(std::strstr(submit.c_str(), ("\nsh '" + out + "/tiny2/slurm/submit.sh'\nsh '" + out +
                                                 "/tiny/slurm/submit.sh'\n").c_str()));
    assert_non_null(std::strstr(slurp(join_path(out, "tiny2/slurm/tasks.sbatch")).c_str(), "/tiny2.toml' --out"));
    assert_non_null(std::strstr(slurp(join_path(out, "tiny/slurm/tasks.sbatch")).c_str(), "--preset 'full' --runs 3 --no-plot"));
    assert_non_null(std::strstr(slurp(join_path(out, "tiny2/run.txt")).c_str(), "\nruns = 3\n"));
    // 3 runs: 3 x (source, direct) + probabilistic = 7 in stage 1, 3 transfers in stage 2
    assert_non_null(std::strstr(slurp(join_path(out, "tiny/slurm/submit.sh")).c_str(), "--array=1-7 tasks.sbatch 1 7)"));

    // The shipped example sweep: three members by name, one submit line each.
    const std::string out2 = join_path(root, "out2");
    assert_int_equal(wait_exit(spawn({"--experiments", SIMEVO_SOURCE_DIR "/experiments", "slurm",
                                      SIMEVO_SOURCE_DIR "/sweeps/open-to-dense-noise.toml", "--out", out2, "--preset", "quick"},
                                     join_path(root, "s2.err"))), 0);
    assert_non_null(std::strstr(slurp(join_path(out2, "open-to-dense.noise-0.1/run.txt")).c_str(), "\nvary = noise=0.1\n"));
    const std::string all = slurp(join_path(out2, "open-to-dense-noise/slurm/submit.sh"));
    assert_non_null(std::strstr(all.c_str(), "/open-to-dense.noise-0/slurm/submit.sh'\nsh '"));
    assert_non_null(std::strstr(all.c_str(), "/open-to-dense.noise-0.05/slurm/submit.sh'\nsh '"));
    assert_non_null(std::strstr(all.c_str(), "/open-to-dense.noise-0.1/slurm/submit.sh'\n"));
}

static void test_sweep_file_problems_are_one_line_with_file_and_line(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::string out = join_path(root, "out"), bad = join_path(root, "bad.toml");
    const std::string head = "name = \"s\"\nexperiment = \"" SIMEVO_TEST_DIR "/tiny.toml\"\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {head + "[vary]\nspeed = [1, 2]\n", ":4: [vary]: unknown key 'speed' (one of noise, sectors)"},
        {head + "[vary]\nnoise = [0, 2]\n", ":4: noise: 2 is not in [0, 1]"},
        {head + "[vary]\nsectors = [8, 100000]\n", ":4: sectors: 100000 is not in [0, 360]"},
        {head + "[vary]\nnoise = [0.05, 0.050]\n", ":4: noise: 0.05 is listed twice"},
        {head + "[vary]\nsectors = [8, 8.5]\n", ":4: sectors: expected an integer"},
        {head + "[vary]\nsectors = []\n", ":4: sectors: expected a non-empty list of values"},
        {head + "[vary]\nnoise = [0]\nsectors = [8]\n", ":3: [vary]: give exactly one key"},
        {head, ":1: a sweep needs 'experiments = [...]', or 'experiment' with one [vary] key"},
        {"name = \"s\"\nexperiments = [\"open-to-dense\", \"no-such\"]\n", ":2: experiments: unknown experiment 'no-such'"},
        {"name = \"s\"\nexperiments = [\"" SIMEVO_TEST_DIR "/tiny.toml\", \"" SIMEVO_TEST_DIR "/tiny.toml\"]\n",
         ":2: experiment 'tiny' is in the sweep twice"},
        {"name = \"tiny\"\nexperiments = [\"" SIMEVO_TEST_DIR "/tiny.toml\"]\n", ":2: experiment 'tiny' has the sweep's name"},
        {"name = \"s\"\nexperiments = [\"missing.toml\"]\nruns = 3\n", ":3: unknown key 'runs' in a sweep file"},
        {"name = \"s\"\nexperiments = [\"missing.toml\"]\n", ":2: experiments: " + root + "/missing.toml: no such experiment file"},
    };
    for (const auto &c : cases) {
        write_file_atomic(bad, c.first);
        int st = 0;
        const std::string e = run_for_error({"--experiments", SIMEVO_SOURCE_DIR "/experiments", "run", bad, "--out", out}, st);
        if (e.find(bad + c.second) == std::string::npos) {
            print_error("expected '%s%s', got: %s", bad.c_str(), c.second.c_str(), e.c_str());
        }
        assert_int_equal(st, 2);
        assert_one_line_containing(e, (bad + c.second).c_str());
    }
    assert_false(file_exists(out));

    int st = 0;
    write_noise_sweep(bad);
    assert_one_line_containing(run_for_error({"run", bad, "--vary", "noise=0.1", "--out", out}, st),
                               "--vary: not with a sweep file");
    assert_int_equal(st, 2);
    assert_one_line_containing(run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--vary", "noise= 0.1", "--out", out}, st),
                               "--vary: ' 0.1' is not a number");
    assert_int_equal(st, 2);
    assert_one_line_containing(run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--vary", "speed=1", "--out", out}, st),
                               "--vary: 'speed=1' is not KEY=VALUE with KEY one of noise, sectors");
    assert_int_equal(st, 2);
    // Issue 20: bounds and whole numbers printed as integers, not 1e+05 and 3.6e+02.
    assert_one_line_containing(run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--vary", "sectors=100000", "--out", out}, st),
                               "sectors: 100000 is not in [0, 360]");
    assert_int_equal(st, 2);
    assert_one_line_containing(run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--vary", "sectors=2.5", "--out", out}, st),
                               "sectors: 2.5 is not a whole number");
    assert_int_equal(st, 2);
    assert_false(file_exists(out));
    // A whole value names its member folder as an integer too.
    assert_int_equal(wait_exit(spawn({"slurm", SIMEVO_TEST_DIR "/tiny.toml", "--vary", "sectors=100", "--out", out},
                                     join_path(root, "v.err"))),
                     0);
    assert_true(file_exists(join_path(out, "tiny.sectors-100/run.txt")));
}

/* The progress redraws of simevo running tiny.toml on a terminal of the given width: the
 * pieces between "\r" and "\n", without the erase-line escape. */
static std::vector<std::string> progress_redraws(unsigned short columns)
{
    const std::string root = make_tmp_dir();
    struct winsize ws {};
    ws.ws_col = columns;
    ws.ws_row = 24;
    int master = -1, slave = -1;
    assert_int_equal(openpty(&master, &slave, nullptr, nullptr, &ws), 0);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        dup2(slave, 2);
        const int nul = open("/dev/null", O_WRONLY);
        dup2(nul, 1);
        close(master);
        setenv("QNAV_DATA_DIR", SIMEVO_SOURCE_DIR "/data", 1);
        unsetenv("COLUMNS");
        const std::string out = join_path(root, "out");
        execl(SIMEVO_EXE, SIMEVO_EXE, "run", SIMEVO_TEST_DIR "/tiny.toml", "--no-plot", "-j", "1", "--out", out.c_str(),
              static_cast<char *>(nullptr));
        _exit(127);
    }
    close(slave);
    std::string text;
    char buf[4096];
    for (;;) {
        const ssize_t n = read(master, buf, sizeof buf);
        if (n > 0) {
            text.append(buf, static_cast<std::size_t>(n));
        } else if (n < 0 && errno == EINTR) {
            continue;
        } else {
            break; /* EIO: simevo exited and the pty's last user is gone */
        }
    }
    close(master);
    assert_int_equal(wait_exit(pid), 0);
    std::vector<std::string> pieces;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= text.size(); ++i) {
        if (i == text.size() || text[i] == '\r' || text[i] == '\n') {
            std::string piece = text.substr(start, i - start);
            if (piece.rfind("\033[K", 0) == 0) {
                piece.erase(0, 3);
            }
            if (!piece.empty()) {
                pieces.push_back(piece);
            }
            start = i + 1;
        }
    }
    return pieces;
}

static std::size_t columns_of(const std::string &s)
{
    std::size_t chars = 0;
    for (char c : s) {
        chars += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    }
    return chars;
}

/* On a 40-column terminal every progress redraw fits in 39 columns (a longer line wraps,
 * and each redraw then scrolls a line instead of replacing it). */
static void test_progress_line_is_cut_to_the_terminal_width(void **state)
{
    (void)state;
    std::size_t longest = 0;
    const std::vector<std::string> pieces = progress_redraws(40);
    for (const std::string &p : pieces) {
        longest = std::max(longest, columns_of(p));
    }
    print_message("%zu progress redraws, the longest %zu columns\n", pieces.size(), longest);
    assert_true(pieces.size() >= 1);
    assert_int_equal(longest, 39); /* cut (even the shortest form is longer), never more */
}

/* Issue 21: at 80 columns the line was cut inside "best R:", so no condition's best R was
 * ever seen. Now the name, counts and rate give way first: the last redraw fits in 79
 * columns and shows the best R of each of tiny.toml's three conditions (its label, full or
 * abbreviated as "s-open", and a number). */
static void test_progress_line_at_80_columns_shows_every_best_r(void **state)
{
    (void)state;
    const std::vector<std::string> pieces = progress_redraws(80);
    assert_true(pieces.size() >= 1);
    for (const std::string &p : pieces) {
        assert_true(columns_of(p) <= 79);
    }
    const std::string &last = pieces.back();
    print_message("last redraw: %s\n", last.c_str());
    assert_true(std::regex_search(last, std::regex("(^| )(best )?R: ")));
    for (const char *label : {"direct", "(source|s)-open", "(transfer|t)-open"}) {
        const std::regex value(std::string(" ") + label + " -?[0-9]+\\.[0-9]+( |$)");
        if (!std::regex_search(last, value)) {
            fail_msg("no best R of %s in \"%s\"", label, last.c_str());
        }
    }
    assert_true(last.find("100") != std::string::npos); /* the percentage is kept */
}

int main(int argc, char **argv)
{
    if (argc > 1) {
        cmocka_set_test_filter(argv[1]); /* e.g. test_slurm_*: one test while working on it */
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_task_stopped_and_resumed_matches_uninterrupted_bytes),
        cmocka_unit_test(test_candidate_and_parent_face_the_same_k_episodes_and_the_budget_counts_episodes),
        cmocka_unit_test(test_checkpoints_resume_to_identical_bytes_even_when_a_row_is_missing),
        cmocka_unit_test(test_es_task_shares_worlds_per_iteration_and_resumes_to_identical_bytes),
        cmocka_unit_test(test_transfer_task_resumes_from_source_file_and_refuses_other_settings),
        cmocka_unit_test(test_experiment_results_do_not_depend_on_thread_count_and_summary_reads_them),
        cmocka_unit_test(test_program_rejects_bad_input_with_one_line),
        cmocka_unit_test(test_program_killed_by_pid_resumes_to_identical_results),
        cmocka_unit_test(test_shares_in_separate_processes_merge_to_the_local_run_byte_for_byte),
        cmocka_unit_test(test_slurm_scripts_run_stage_two_after_stage_one_and_keep_foreign_files),
        cmocka_unit_test(test_slurm_refuses_values_that_would_break_an_sbatch_line),
        cmocka_unit_test(test_fit_source_is_written_once_and_transfers_start_from_it),
        cmocka_unit_test(test_table_mode_and_network_mode_give_identical_results),
        cmocka_unit_test(test_atomic_write_never_follows_a_planted_symlink),
        cmocka_unit_test(test_plot_child_dies_when_simevo_is_killed),
        cmocka_unit_test(test_program_command_line_names_unknown_options_and_subcommands),
        cmocka_unit_test(test_program_refuses_zero_episodes_and_impossible_noise),
        cmocka_unit_test(test_experiment_file_problems_are_found_before_any_output),
        cmocka_unit_test(test_progress_line_is_cut_to_the_terminal_width),
        cmocka_unit_test(test_progress_line_at_80_columns_shows_every_best_r),
        cmocka_unit_test(test_sweep_shares_merge_to_the_member_experiment_run_directly_with_its_variation),
        cmocka_unit_test(test_slurm_sweep_writes_each_members_scripts_and_one_submit_for_all),
        cmocka_unit_test(test_sweep_file_problems_are_one_line_with_file_and_line),
        cmocka_unit_test(test_generalist_quick_run_writes_the_recommended_policy_and_its_test_lines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
