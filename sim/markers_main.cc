// mcmt-markers: printable marker sheets at exact size (PDF or PNG).
#include <iostream>

#include "core/cli.h"
#include "core/config.h"
#include "core/dictionary.h"
#include "sim/marker_sheet.h"

int main(int argc, char** argv) {
  return mcmt::RunMain("mcmt-markers", [&] {
    std::string out, config, dictionary = "DICT_6X6_250", ids = "0-3", page = "a4";
    double size = 0.04, dpi = 600, margin = 10;
    bool inverted = false;
    mcmt::ArgParser args("mcmt-markers", "Writes printable marker sheets at exact size (PDF or PNG).");
    args.AddString("out", &out, "output file: .pdf (exact size) or .png (at --dpi)", true);
    args.AddString("config", &config, "take dictionary, size, per-id sizes and ids from this rig YAML");
    args.AddString("dictionary", &dictionary, "OpenCV dictionary name or dictionary file");
    args.AddString("ids", &ids, "ids to print, e.g. 0-9,12");
    args.AddDouble("size", &size, "marker side in metres (the black square, without the white border)");
    args.AddFlag("inverted", &inverted, "white-on-black markers (--config: markers.inverted)");
    args.AddString("page", &page, "page size: a4 or letter");
    args.AddDouble("margin-mm", &margin, "page margin in millimetres");
    args.AddDouble("dpi", &dpi,
                   "PNG resolution; given, it must make every marker cell whole pixels (else the error names "
                   "the nearest exact dpi); left out, the nearest exact dpi to 600 is used");
    args.AddEpilog(
        "Print at 100 % (\"actual size\", no fit-to-page). Every page says what to measure and has a 100 mm\n"
        "scale bar: check it and one marker with a ruler. --config also takes markers.inverted "
        "(white-on-black).\n"
        "example: mcmt-markers --config rig.yaml --out markers.pdf\n");
    int code = 0;
    if (!args.Parse(argc, argv, &code)) return code;
    mcmt::sim::MarkerSheetOptions o;
    o.page = page;
    o.margin_mm = margin;
    o.dpi = dpi;
    o.exact_dpi = args.Given("dpi");
    if (!config.empty()) {
      const mcmt::RigConfig rig = mcmt::LoadRigConfig(config);
      o.dictionary = rig.markers.dictionary;
      o.sizes = rig.markers.Sizes();
      o.ids = rig.markers.ids;
      o.inverted = rig.markers.inverted;
    }
    if (inverted) o.inverted = true;
    if (config.empty() || args.Given("dictionary")) o.dictionary = dictionary;
    if (config.empty() || args.Given("size")) o.sizes.default_size = size;
    if (o.ids.empty() || args.Given("ids")) o.ids = mcmt::sim::ParseIdList(ids);
    const std::vector<std::string> files = mcmt::sim::WriteMarkerSheet(out, o);
    for (const std::string& f : files) std::cout << "wrote " << f << "\n";
    if (out.size() > 4 && out.compare(out.size() - 4, 4, ".png") == 0)
      std::cout << "PNG at " << mcmt::sim::PngSheetDpi(o, mcmt::LoadDictionary(o.dictionary)->markerSize + 2)
                << " dpi (every marker cell is whole pixels; the dpi is stored in the file)\n";
    return 0;
  });
}
