/*
 * Tests of simevo's resumable outputs and of the program itself: a task stopped and
 * resumed (with a half-written journal line) ends with the same bytes as an uninterrupted
 * one; a journal from other settings is refused; the simevo program killed by its pid in
 * the middle of a run and started again ends with files identical to an uninterrupted
 * run; an experiment on 1 and 3 threads gives the same files and its summary matches
 * them; table mode and network mode give byte-identical results; and bad input (unknown
 * experiment, malformed spec, missing or incompatible policy file, a folder made with other
 * settings) gives one line and a non-zero exit without a summary.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

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
#include <functional>
#include <map>
#include <string>
#include <sys/file.h>
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

static RunnerFactory fake_factory()
{
    return [](const Scenario &, uint64_t) -> std::unique_ptr<EpisodeRunner> { return std::make_unique<FakeRunner>(); };
}

static void test_task_stopped_and_resumed_matches_uninterrupted_bytes(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    const std::atomic<bool> never{false};
    TaskDef a = fake_task(join_path(root, "a"));
    assert_true(run_task(a, "", fake_factory(), TaskObserver{}, never));

    TaskDef b = fake_task(join_path(root, "b"));
    std::atomic<bool> stop{false};
    uint64_t seen = 0;
    TaskObserver obs;
    obs.episodes_done = [&](uint64_t n, bool) {
        seen += n;
        if (seen >= 137) {
            stop = true;
        }
    };
    assert_false(run_task(b, "", fake_factory(), obs, stop));
    assert_false(file_exists(join_path(b.dir, "done")));
    assert_false(file_exists(join_path(b.dir, "best.policy")));
    // A kill in the middle of a write leaves half a line behind.
    FILE *f = std::fopen(join_path(b.dir, "episodes.csv").c_str(), "a");
    std::fputs("137,-3.2500000", f);
    std::fclose(f);
    uint64_t replayed = 0;
    TaskObserver obs2;
    obs2.episodes_done = [&](uint64_t n, bool r) { replayed += r ? n : 0; };
    assert_true(run_task(b, "", fake_factory(), obs2, never));
    assert_int_equal(replayed, 137); // resumed from the journal, not re-simulated

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
    TaskObserver obs;
    obs.episodes_done = [&](uint64_t n, bool) {
        seen += n;
        if (seen >= 70) {
            stop = true;
        }
    };
    assert_false(run_task(b, "", fake_factory(), obs, stop));
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

static void test_experiment_results_do_not_depend_on_thread_count_and_summary_reads_them(void **state)
{
    (void)state;
    const std::string root = make_tmp_dir();
    ExperimentSpec spec = parse_experiment(R"(name = "fake"
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
    assert_int_equal(S.conditions.size(), 4); // transfer-a, transfer-b, direct, probabilistic
    assert_int_equal(S.comparisons.size(), 5);
    const ConditionSummary &direct = S.conditions[2];
    assert_string_equal(direct.label.c_str(), "direct");
    assert_int_equal(direct.final_per_run.size(), 3);
    assert_int_equal(direct.curve_mean.size(), 5);
    std::vector<double> r;
    for (const auto &o : read_eval(join_path(root, "one/run-002/direct/eval.csv"))) {
        r.push_back(o.R);
    }
    assert_true(std::fabs(direct.final_per_run[1] - mean_of(r)) < 1e-12);
    assert_int_equal(S.conditions[3].final_per_run.size(), 7); // probabilistic: per episode
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
    for (int i = 0; i < 20000 && !killed; ++i) {
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

    // While another process holds the folder's lock, simevo refuses to touch it.
    const int lfd = open(join_path(a, "tiny/.lock").c_str(), O_RDWR);
    assert_true(lfd >= 0 && flock(lfd, LOCK_EX | LOCK_NB) == 0);
    assert_int_equal(wait_exit(spawn(with_out(a), join_path(root, "lock.err"))), 1);
    assert_non_null(std::strstr(slurp(join_path(root, "lock.err")).c_str(), "another simevo is running in this folder"));
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
    assert_int_equal(st, 1);
    assert_one_line_containing(e, "unknown experiment 'no-such-experiment'");

    const std::string bad = join_path(root, "bad.toml");
    write_file_atomic(bad, "name = \"bad\"\n[target]\nsectors = 32\nspeed = 3\n");
    e = run_for_error({"run", bad, "--out", root}, st);
    assert_int_equal(st, 1);
    assert_one_line_containing(e, (bad + ":4: unknown key 'speed' in [target]").c_str());

    const std::string missing = join_path(root, "missing.toml");
    write_file_atomic(missing, "name = \"missing\"\n[target]\nepisodes = 5\n[[source]]\nlabel = \"f\"\npolicy = \"" +
                                   root + "/nope.policy\"\n");
    e = run_for_error({"run", missing, "--out", root, "--no-plot"}, st);
    assert_int_equal(st, 1);
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
    assert_int_equal(st, 1);
    assert_one_line_containing(e, "incompatible policy");
    assert_false(file_exists(join_path(root, "inc/summary.md")));

    e = run_for_error({"run", SIMEVO_TEST_DIR "/tiny.toml", "--preset", "nope", "--out", root}, st);
    assert_int_equal(st, 1);
    assert_one_line_containing(e, "no preset 'nope'");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_task_stopped_and_resumed_matches_uninterrupted_bytes),
        cmocka_unit_test(test_candidate_and_parent_face_the_same_k_episodes_and_the_budget_counts_episodes),
        cmocka_unit_test(test_checkpoints_resume_to_identical_bytes_even_when_a_row_is_missing),
        cmocka_unit_test(test_transfer_task_resumes_from_source_file_and_refuses_other_settings),
        cmocka_unit_test(test_experiment_results_do_not_depend_on_thread_count_and_summary_reads_them),
        cmocka_unit_test(test_program_rejects_bad_input_with_one_line),
        cmocka_unit_test(test_program_killed_by_pid_resumes_to_identical_results),
        cmocka_unit_test(test_table_mode_and_network_mode_give_identical_results),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
