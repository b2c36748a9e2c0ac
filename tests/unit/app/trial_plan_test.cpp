// Sweeps, trial plans and the Slurm executor's pure parts (issue 25), without a cluster: parsing
// `--set KEY=V1,V2`, the cartesian product, plan.json written and read back, why a trial has no
// result, the job array's index lists, and running a helper program.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "slurm_executor.hpp"
#include "subprocess.hpp"
#include "support/temp_dir.hpp"
#include "sweep.hpp"
#include "trial_plan.hpp"

namespace aerotrack::app {
namespace {

void writeText(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

TEST(Sweep, GivenValuesThenCommasOutsideBracketsAndQuotesSplitThem) {
  const auto k = parseSweepOption("planning.goal.offset=[1, 2],[3, 4],'a,b',5");
  ASSERT_TRUE(k) << k.error().message;
  EXPECT_EQ(k->key, "planning.goal.offset");
  EXPECT_EQ(k->values, (std::vector<std::string>{"[1, 2]", "[3, 4]", "'a,b'", "5"}));
  EXPECT_EQ(parseSweepOption("a=1,,2").error().message, "--set a: an empty value in '1,,2'");
  EXPECT_EQ(parseSweepOption("a=").error().message, "--set a: an empty value in ''");
  EXPECT_EQ(parseSweepOption("a=1,2,1").error().message, "--set a: value '1' given twice");
  EXPECT_EQ(parseSweepOption("a").error().message, "--set: expected KEY=VALUE, got 'a'");
}

TEST(Sweep, GivenKeysThenTheProductHasEveryCombinationFirstKeySlowest) {
  const auto points = sweepPoints({{"a", {"1", "2"}}, {"b.c", {"x", "y", "z"}}}, 100);
  ASSERT_TRUE(points);
  ASSERT_EQ(points->size(), 6U);
  EXPECT_EQ(sweepPointLabel((*points)[0]), "a=1, b.c=x");
  EXPECT_EQ(sweepPointLabel((*points)[2]), "a=1, b.c=z");
  EXPECT_EQ(sweepPointLabel((*points)[3]), "a=2, b.c=x");
  EXPECT_EQ(sweepPointId((*points)[5]), "a=2+b.c=z");
  EXPECT_EQ(sweepArgs((*points)[5]), (std::vector<std::string>{"--set", "a=2", "--set", "b.c=z"}));
  EXPECT_EQ(sweepPointId({{"k", "[1, 2]/x"}}), "k=_1__2__x");  // folder-safe
  const auto none = sweepPoints({}, 100);
  ASSERT_TRUE(none);
  EXPECT_EQ(none->size(), 1U);
  EXPECT_TRUE(none->front().empty());
  EXPECT_EQ(sweepPoints({{"a", {"1"}}, {"a", {"2"}}}, 100).error().message, "--set a: the key is swept twice");
  EXPECT_FALSE(sweepPoints({{"a", {"1", "2", "3"}}, {"b", {"1", "2", "3"}}}, 8));
}

TrialPlan examplePlan(const std::string& dir) {
  TrialPlan plan;
  plan.kind = "suite";
  plan.out_dir = dir;
  plan.binary = "/opt/aerotrack/bin/aerotrack";
  plan.suite.name = "s";
  plan.suite.source = "s.yaml";
  plan.suite.first_seed = 3;
  plan.suite.last_seed = 4;
  plan.suite.targets.followed_rate = 0.9;
  SuiteCell cell;
  cell.scenario = "sharp_turn";
  cell.speed_mps = 1.5;
  cell.mode = "proposed";
  cell.camera = "keypoints";
  cell.id = "sharp_turn-1.5mps-proposed-keypoints";
  SuiteCell broken = cell;
  broken.scenario = "/nowhere/x.yaml";
  broken.id = "x";
  plan.suite.cells = {cell, broken};
  plan.sweep = {{"planning.goal.tracking_distance_m", {"2", "3"}}};
  applySweep(plan.suite, *sweepPoints(plan.sweep, 10));
  plan.cell_errors = {"", "", "scenario file /nowhere/x.yaml does not exist",
                      "scenario file /nowhere/x.yaml does not exist"};
  plan.slurm = SlurmSettings{"debug", 5, 512, 4, {"--qos=low"}};
  planTrials(plan);
  return plan;
}

TEST(TrialPlan, GivenAPlanThenItIsWrittenAndReadBackWithEveryTrial) {
  test::TempDir dir;
  const TrialPlan plan = examplePlan(dir.path());
  ASSERT_EQ(plan.suite.cells.size(), 4U);
  EXPECT_EQ(plan.suite.cells[1].id, "sharp_turn-1.5mps-proposed-keypoints-planning.goal.tracking_distance_m=3");
  ASSERT_EQ(plan.trials.size(), 4U);  // 2 cells x 2 seeds; the broken cell's trials are not planned
  EXPECT_EQ(plan.trials[3].dir, dir.path() + "/" + plan.suite.cells[1].id + "/trial-4");
  ASSERT_TRUE(writePlan(plan));
  const auto back = readPlan(dir.path());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->kind, "suite");
  EXPECT_EQ(back->binary, plan.binary);
  ASSERT_EQ(back->trials.size(), 4U);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(trialCommand(*back, i), trialCommand(plan, i));
  EXPECT_EQ(back->suite.cells[1].sets.front().value, "3");
  EXPECT_EQ(back->suite.targets.followed_rate, 0.9);
  ASSERT_TRUE(back->slurm);
  EXPECT_EQ(back->slurm->options, (std::vector<std::string>{"--qos=low"}));
  const std::vector<std::string> command = trialCommand(plan, 3);
  EXPECT_EQ(command, (std::vector<std::string>{plan.binary, "sim", "--scenario", "sharp_turn", "--seed", "4", "--out",
                                               plan.trials[3].dir, "--mode", "proposed", "--camera", "keypoints",
                                               "--speed", "1.5", "--set", "planning.goal.tracking_distance_m=3"}));
  // trials.txt: line i + 1 is trial i's command, quoted for sh.
  std::ifstream lines(dir.path() + "/trials.txt");
  std::string line;
  for (int i = 0; i < 4; ++i) std::getline(lines, line);
  EXPECT_NE(line.find("exec '/opt/aerotrack/bin/aerotrack' 'sim' '--scenario' 'sharp_turn' '--seed' '4'"),
            std::string::npos);
  EXPECT_FALSE(std::getline(lines, line));
}

TEST(TrialPlan, GivenABrokenPlanFileThenOneLineNamesIt) {
  test::TempDir dir;
  EXPECT_EQ(readPlan(dir.path()).error().message,
            dir.path() + "/plan.json: cannot open file: no such file or directory");
  writeText(dir.path() + "/plan.json", "{\"format\": \"aerotrack-trial-plan-1\", \"kind\": \"bench\"");
  EXPECT_EQ(readPlan(dir.path()).error().message, dir.path() + "/plan.json: not valid JSON (cut off?)");
  writeText(dir.path() + "/plan.json", "{\"format\": \"other\"}");
  EXPECT_NE(readPlan(dir.path()).error().message.find("not a trial plan of this version"), std::string::npos);
  writeText(dir.path() + "/plan.json", "{\"format\": \"aerotrack-trial-plan-1\", \"kind\": \"suite\"}");
  EXPECT_NE(readPlan(dir.path()).error().message.find("plan.json: "), std::string::npos);
}

TEST(TrialPlan, GivenAPlanThatMovedThenItsTrialsAreUnderItsNewFolder) {
  test::TempDir dir;
  const TrialPlan plan = examplePlan(dir.path() + "/old");
  ASSERT_TRUE(std::filesystem::create_directories(plan.out_dir));
  ASSERT_TRUE(writePlan(plan));
  std::filesystem::rename(plan.out_dir, dir.path() + "/new");
  const auto moved = readPlan(dir.path() + "/new");
  ASSERT_TRUE(moved) << moved.error().message;
  EXPECT_EQ(moved->trials[0].dir.rfind(dir.path() + "/new/", 0), 0U) << moved->trials[0].dir;
}

TEST(TrialPlan, GivenEachWayATrialCanEndThenItsStateSaysWhy) {
  test::TempDir dir;
  const std::string d = dir.path();
  const std::string complete = R"({"seed": 1, "success": true, "interrupted": false})";
  writeText(d + "/ok/summary.json", complete);
  EXPECT_TRUE(trialState(d + "/ok", "").complete);
  EXPECT_EQ(trialState(d + "/never", "").reason, "not started");
  writeText(d + "/cut/summary.json", R"({"seed": 1, "succ)");
  EXPECT_NE(trialState(d + "/cut", "").reason.find("summary.json is incomplete"), std::string::npos);
  writeText(d + "/stopped/summary.json", R"({"seed": 1, "success": false, "interrupted": true})");
  EXPECT_NE(trialState(d + "/stopped", "").reason.find("interrupted"), std::string::npos);
  writeText(d + "/failed/log.txt", "starting\naerotrack sim: scenario x: no such file\n");
  EXPECT_EQ(trialState(d + "/failed", "").reason, "failed: aerotrack sim: scenario x: no such file");
  writeText(d + "/running/log.txt", "starting\n");
  EXPECT_NE(trialState(d + "/running", "").reason.find("still running, or killed"), std::string::npos);
  // Slurm's word comes first: it knows why a process vanished.
  writeText(d + "/slurm/t.log",
            "aerotrack trial 3\nslurmstepd: error: *** JOB 12 ON n1 CANCELLED AT 2026-11-27T10:00:00 DUE TO TIME "
            "LIMIT ***\n");
  EXPECT_EQ(trialState(d + "/running", d + "/slurm/t.log").reason.rfind("killed by Slurm: time limit", 0), 0U);
  writeText(d + "/slurm/c.log", "slurmstepd: error: *** JOB 13 ON n1 CANCELLED AT 2026-11-27T10:00:00 ***\n");
  EXPECT_EQ(trialState(d + "/running", d + "/slurm/c.log").reason.rfind("cancelled", 0), 0U);
  EXPECT_TRUE(trialState(d + "/ok", d + "/slurm/c.log").complete);  // a result beats an old log
}

TEST(SlurmExecutor, GivenIndicesThenArraysAndTheirSpecsStayUnderMaxArraySize) {
  EXPECT_EQ(compressIndices({0, 1, 2, 3, 7, 9, 10}), "0-3,7,9-10");
  EXPECT_EQ(compressIndices({5}), "5");
  EXPECT_EQ(compressIndices({}), "");
  const auto arrays = splitIntoArrays({0, 1, 999, 1000, 1001, 2500}, 1000);
  ASSERT_EQ(arrays.size(), 3U);
  EXPECT_EQ(arrays[0].first, 0U);
  EXPECT_EQ(arrays[0].second, (std::vector<std::size_t>{0, 1, 999}));
  EXPECT_EQ(arrays[1].first, 1000U);
  EXPECT_EQ(arrays[1].second, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(arrays[2].first, 2500U);
  EXPECT_EQ(arrays[2].second, (std::vector<std::size_t>{0}));
}

TEST(SlurmExecutor, GivenJobsSubmittedThenEachTrialsLatestLogIsFound) {
  test::TempDir dir;
  TrialPlan plan = examplePlan(dir.path());
  writeText(dir.path() + "/slurm/jobs.txt", "41 0 0,1,2,3\n57 2 2\n");
  const auto logs = slurmLogs(plan);
  ASSERT_EQ(logs.size(), 4U);
  EXPECT_EQ(logs.at(1), dir.path() + "/slurm/logs/job41-task1.log");
  EXPECT_EQ(logs.at(2), dir.path() + "/slurm/logs/job57-task0.log");  // resubmitted: the newer job's
}

TEST(Subprocess, GivenAProgramThenItsOutputsAndExitStatusComeBack) {
  const auto r = runProcess({"sh", "-c", "echo out; echo err >&2; exit 3"});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->exit_status, 3);
  EXPECT_EQ(r->out, "out\n");
  EXPECT_EQ(r->err, "err\n");
  EXPECT_EQ(runProcess({"aerotrack-no-such-program"}).error().message, "aerotrack-no-such-program: not found on PATH");
  const auto big = runProcess({"sh", "-c", "head -c 300000 /dev/zero"}, 1000);  // read to the end, kept bounded
  ASSERT_TRUE(big);
  EXPECT_EQ(big->out.size(), 1000U);
  EXPECT_EQ(big->exit_status, 0);
  EXPECT_EQ(firstLine("\n  \nsbatch: error: x\nmore"), "sbatch: error: x");
}

TEST(Subprocess, GivenAnyTextThenShellQuotingGivesItBackUnchanged) {
  for (const std::string text : {"plain", "with space", "it's", "$HOME `x` \"q\" \\ ;|&", ""}) {
    const auto r = runProcess({"sh", "-c", "printf %s " + shellQuote(text)});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->out, text);
  }
}

}  // namespace
}  // namespace aerotrack::app
