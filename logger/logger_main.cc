// mcmt-logger: records mcmt LCM channels into a standard LCM event log (lcm-logplayer plays it).
#include <iostream>

#include "core/cli.h"
#include "core/config.h"
#include "core/lcm_util.h"
#include "core/options.h"
#include "logger/session_logger.h"

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-logger", [&]() {
    mcmt::LoggerOptions o;
    std::string lcm_url;
    long long max_messages = 0;
    bool no_fsync = false;
    double recv_buf_mb = 16;
    mcmt::ArgParser args("mcmt-logger",
                         "Records LCM channels into an LCM event log (lcm-logplayer replays it).");
    args.AddString("out", &o.out, "log file to create, e.g. session.lcmlog (never overwritten)", true);
    args.AddString("channels", &o.channels, "channel regex (LCM anchors it)");
    args.AddString("lcm-url", &lcm_url, "LCM URL (default: lcm.url of --config, else LCM's default)");
    args.AddString("config", &o.config_path, "rig YAML: copied into the sidecar with its intrinsics files");
    args.AddDouble("split-mb", &o.split_mb, "start a new part at this size in MB (1e6 bytes); 0: never");
    args.AddDouble("split-minutes", &o.split_minutes, "start a new part after this many minutes; 0: never");
    args.AddInt("flush-ms", &o.flush_ms, "write and sync to disk every this many milliseconds");
    args.AddFlag("no-fsync", &no_fsync,
                 "flush to the kernel only (survives a crash of the logger, not of the machine)");
    args.AddDouble("max-seconds", &o.max_seconds, "stop after this many seconds; 0: until SIGINT/SIGTERM");
    args.AddInt64("max-messages", &max_messages, "stop after recording this many messages; 0: no limit");
    args.AddInt("queue-capacity", &o.queue_capacity, "LCM subscription queue, messages (LCM's default: 30)");
    args.AddDouble(
        "recv-buf-mb", &recv_buf_mb,
        "udpm: socket receive buffer to ask for (recv_buf_size) unless the URL sets one; 0: leave it",
        mcmt::InRange(0, 1e6));
    args.AddDouble("status-seconds", &o.status_seconds, "status line interval on stderr; 0: quiet");
    args.AddEpilog(
        "Files: without splitting exactly --out; with --split-mb/--split-minutes the parts are "
        "NAME.00.lcmlog,\n"
        "NAME.01.lcmlog, ... Sidecar: NAME.yaml (config, start/end, per-channel counts, losses), refreshed\n"
        "while recording. An existing log, part or sidecar is never overwritten: the logger refuses to "
        "start.\n"
        "SIGINT/SIGTERM close the log cleanly; after kill -9 every event up to the last flush is readable.\n"
        "Settings may also come from the rig YAML's logger: section (--help-config lists its keys); the\n"
        "command line wins.\n\n"
        "example: mcmt-logger --out session.lcmlog --config rig.yaml --split-mb 500\n");
    args.SetConfigHelp("### logger\n\n" + mcmt::LoggerOptionTable().Markdown());
    int code = 0;
    if (!args.Parse(argc, argv, &code)) return code;

    mcmt::LoggerOptions options;  // defaults <- rig YAML logger: section <- command line
    std::string url;
    if (!o.config_path.empty()) {
      mcmt::RigConfig rig = mcmt::LoadRigConfig(o.config_path);
      mcmt::LoadLoggerOptions(rig.logger, &options);
      url = rig.lcm_url;
    }
    options.out = o.out;
    options.config_path = o.config_path;
    if (args.Given("channels")) options.channels = o.channels;
    if (args.Given("split-mb")) options.split_mb = o.split_mb;
    if (args.Given("split-minutes")) options.split_minutes = o.split_minutes;
    if (args.Given("flush-ms")) options.flush_ms = o.flush_ms;
    if (no_fsync) options.fsync = false;
    if (args.Given("queue-capacity")) options.queue_capacity = o.queue_capacity;
    if (args.Given("status-seconds")) options.status_seconds = o.status_seconds;
    options.max_seconds = o.max_seconds;
    options.max_messages = max_messages;
    if (args.Given("lcm-url")) url = lcm_url;
    long long recv_buf = static_cast<long long>(recv_buf_mb * 1e6);
    const long long cap = mcmt::KernelReceiveBufferMax();
    if (cap > 0 && recv_buf > cap) recv_buf = cap;  // the kernel would cap it anyway
    std::string note;
    const std::string effective = mcmt::WithReceiveBuffer(url, recv_buf);
    if (effective != url) {
      if (recv_buf < 1000000)
        note = "mcmt-logger: note: the kernel caps socket receive buffers at " + std::to_string(cap / 1000) +
               " kB (net.core.rmem_max); for image rates raise it: sysctl -w net.core.rmem_max=16000000";
      url = effective;
    }
    options.lcm_url = url;

    std::unique_ptr<lcm::LCM> lcm = mcmt::OpenLcm(url);
    mcmt::SessionLogger logger(*lcm, options);
    const mcmt::StopToken stop = mcmt::StopOnSignals();
    if (!note.empty()) std::cerr << note << std::endl;
    std::cerr << "mcmt-logger: recording " << options.channels << " into " << logger.current_part()
              << " (sidecar " << logger.sidecar_path() << ")" << std::endl;
    logger.Run(stop);
    return 0;
  });
}
