// slamaware-ctl query [--label L | --region x0 y0 z0 x1 y1 z1] [--map-id N] [--timeout s]: asks the
// object map server (OBJECT_QUERY) and prints its answer (OBJECT_QUERY_REPLY) as a table.
// slamaware-ctl label OBJECT_ID CLASS | label --unlabel OBJECT_ID: gives an object the user's class
// (kept with it and saved at once), or takes it back.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>

#include "common/bus/bus.h"
#include "common/bus/shutdown.h"
#include "slamaware/object_query_reply_t.hpp"
#include "slamaware/object_query_t.hpp"
#include "tools/ctl/ctl_commands.h"

namespace slamaware {

namespace {

using Clock = std::chrono::steady_clock;

struct QueryArgs {
  int8_t kind = object_query_t::KIND_ALL;
  int32_t object_id = -1;
  std::string label;
  std::vector<double> region;
  int map_id = -1;
  double timeout_s = 3.0;
  bool hide_background = false;
};

void printReply(const object_query_reply_t& r, bool hide_background) {
  size_t hidden = 0;
  for (const auto& o : r.objects) hidden += hide_background && o.label == "background";
  if (r.objects.size() == hidden) {
    std::printf("no objects%s\n",
                hidden ? (" (" + std::to_string(hidden) + " background candidates)").c_str() : "");
    return;
  }
  std::printf("%6s  %-16s %6s %6s  %-26s %-20s %7s %4s  %s\n", "ID", "LABEL", "P", "VIEWS",
              "CENTROID (x y z)", "EXTENT (x y z)", "VOXELS", "MAP", "USER LABEL");
  for (const auto& o : r.objects) {
    if (hide_background && o.label == "background") continue;
    float p = 0;
    for (size_t c = 0; c < r.class_names.size() && c < o.posterior.size(); ++c)
      if (r.class_names[c] == o.label) p = o.posterior[c];
    char centroid[64], extent[64];
    if (std::isfinite(o.centroid[0])) {
      std::snprintf(centroid, sizeof(centroid), "%7.3f %7.3f %7.3f", o.centroid[0], o.centroid[1],
                    o.centroid[2]);
      std::snprintf(extent, sizeof(extent), "%5.3f %5.3f %5.3f", o.extent[0], o.extent[1],
                    o.extent[2]);
    } else {
      std::snprintf(centroid, sizeof(centroid), "(not localised)");
      std::snprintf(extent, sizeof(extent), "-");
    }
    std::printf("%6d  %-16s %6.3f %6d  %-26s %-20s %7d %4d  %s\n", o.id, o.label.c_str(), p,
                o.num_views, centroid, extent, o.num_voxels, o.map_id, o.user_label.c_str());
  }
  if (hidden) std::printf("(and %zu background candidates)\n", hidden);
}

int runQuery(const NodeArgs& node, const QueryArgs& args) {
  const SystemConfig sys = loadSystem(node);
  Bus bus(sys.bus.url);
  object_query_t q{};
  std::random_device rd;
  q.request_id = (static_cast<int64_t>(::getpid()) << 32) ^ static_cast<int64_t>(rd());
  q.map_id = args.map_id;
  q.kind = args.kind;
  q.object_id = args.object_id;
  if (args.kind == object_query_t::KIND_LABEL || args.kind == object_query_t::KIND_UNLABEL) {
    q.label = args.label;  // idempotent too: sent again until answered
  } else if (!args.label.empty()) {
    q.kind = object_query_t::KIND_BY_LABEL;
    q.label = args.label;
  } else if (!args.region.empty()) {
    q.kind = object_query_t::KIND_BY_REGION;
    for (int i = 0; i < 3; ++i) {
      q.region_min[i] =
          std::min(args.region[static_cast<size_t>(i)], args.region[static_cast<size_t>(i + 3)]);
      q.region_max[i] =
          std::max(args.region[static_cast<size_t>(i)], args.region[static_cast<size_t>(i + 3)]);
    }
  }
  std::optional<object_query_reply_t> reply;
  bus.subscribe<object_query_reply_t>(sys.channels.object_query_reply,
                                      [&](const object_query_reply_t& r) {
                                        if (r.request_id == q.request_id) reply = r;
                                      });
  // A query is idempotent: it is sent again every 0.5 s until answered (a datagram may be lost).
  const auto start = Clock::now();
  auto last_sent = start - std::chrono::seconds(1);
  while (!reply && !shutdownRequested() &&
         Clock::now() - start < std::chrono::duration<double>(args.timeout_s)) {
    if (Clock::now() - last_sent >= std::chrono::milliseconds(500)) {
      q.utime = wallUtime();
      bus.publish(sys.channels.object_query, q);
      last_sent = Clock::now();
    }
    bus.handle(20);
  }
  if (!reply) {
    std::fprintf(stderr, "no answer on %s within %.1f s (is slamaware-objectmap running on %s?)\n",
                 sys.channels.object_query_reply.c_str(), args.timeout_s, sys.bus.url.c_str());
    return 1;
  }
  if (!reply->error.empty()) {
    std::fprintf(stderr, "%s refused: %s\n",
                 args.kind >= object_query_t::KIND_LABEL ? "label" : "query", reply->error.c_str());
    return 1;
  }
  printReply(*reply, args.hide_background);
  return 0;
}

}  // namespace

void addQueryCommand(CLI::App& app, CtlContext& ctx) {
  auto args = std::make_shared<QueryArgs>();
  auto* sub =
      app.add_subcommand("query", "ask the object map: every object, by label or by region");
  auto* label =
      sub->add_option("--label", args->label, "objects whose label (argmax class) is this");
  sub->add_option("--region", args->region,
                  "objects whose box meets the box x0 y0 z0 x1 y1 z1 (map units)")
      ->expected(6)
      ->excludes(label);
  sub->add_option("--map-id", args->map_id, "only this map segment (-1: all)");
  sub->add_option("--timeout", args->timeout_s, "s to wait for the answer");
  sub->add_flag("--hide-background", args->hide_background,
                "leave out the candidates whose fused label is background (counted at the end)");
  sub->callback([&ctx, args] {
    ctx.exit_code = runNode("ctl", ctx.node, [&] { return runQuery(ctx.node, *args); });
  });

  auto largs = std::make_shared<QueryArgs>();
  auto unlabel = std::make_shared<bool>(false);
  auto* lab = app.add_subcommand(
      "label",
      "give an object of the map your class name (saved with the map; slamaware-harvest "
      "collects its views), or take it back with --unlabel");
  lab->add_option("object_id", largs->object_id, "the object's id (slamaware-ctl query)")
      ->required();
  lab->add_option("class", largs->label, "class name: letters, digits, _ or -");
  lab->add_flag("--unlabel", *unlabel, "take the object's label back");
  lab->add_option("--timeout", largs->timeout_s, "s to wait for the answer");
  lab->callback([&ctx, largs, unlabel] {
    if (*unlabel == !largs->label.empty()) {
      std::fprintf(stderr, "label: give OBJECT_ID CLASS, or --unlabel OBJECT_ID\n");
      ctx.exit_code = 2;
      return;
    }
    largs->kind = *unlabel ? object_query_t::KIND_UNLABEL : object_query_t::KIND_LABEL;
    ctx.exit_code = runNode("ctl", ctx.node, [&] { return runQuery(ctx.node, *largs); });
  });
}

}  // namespace slamaware
