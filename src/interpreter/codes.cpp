#include "interpreter/codes.hpp"

namespace cncore::interp {

namespace {
constexpr CodeInfo ok(GGroup g, const char* name) {
  return {true, true, static_cast<int>(g), name};
}
constexpr CodeInfo no(GGroup g, const char* name) {
  return {true, false, static_cast<int>(g), name};
}
constexpr CodeInfo okm(MGroup g, const char* name) {
  return {true, true, static_cast<int>(g), name};
}
}  // namespace

// Size: the table of every G code cncore knows, one case per code, in numeric order; a lookup
// table split in parts would only be harder to search.
CodeInfo g_code_info(int code10) {
  switch (code10) {
    case 0:
      return ok(GGroup::kMotion, "rapid move");
    case 10:
      return ok(GGroup::kMotion, "linear move");
    case 20:
      return ok(GGroup::kMotion, "clockwise arc");
    case 30:
      return ok(GGroup::kMotion, "counter-clockwise arc");
    case 40:
      return ok(GGroup::kNonModal, "dwell");
    case 50:
      return ok(GGroup::kMotion, "cubic spline");
    case 51:
      return ok(GGroup::kMotion, "quadratic spline");
    case 52:
      return ok(GGroup::kMotion, "NURBS block");
    case 53:
      return ok(GGroup::kMotion, "end of a NURBS block");
    case 70:
      return ok(GGroup::kLatheDiameter, "lathe diameter mode");
    case 80:
      return ok(GGroup::kLatheDiameter, "lathe radius mode");
    case 90:
      return ok(GGroup::kExactStopOnce, "exact stop");
    case 100:
      return ok(GGroup::kNonModal, "set coordinate data");
    case 170:
      return ok(GGroup::kPlane, "XY plane");
    case 180:
      return ok(GGroup::kPlane, "ZX plane");
    case 190:
      return ok(GGroup::kPlane, "YZ plane");
    case 171:
    case 181:
    case 191:
      return no(GGroup::kPlane, "UVW plane selection");
    case 200:
      return ok(GGroup::kUnits, "inch units");
    case 210:
      return ok(GGroup::kUnits, "mm units");
    case 280:
      return ok(GGroup::kNonModal, "return to the G28 home position");
    case 281:
      return ok(GGroup::kNonModal, "store the G28 home position");
    case 300:
      return ok(GGroup::kNonModal, "return to the G30 home position");
    case 301:
      return ok(GGroup::kNonModal, "store the G30 home position");
    case 330:
      return ok(GGroup::kMotion, "spindle-synchronised motion");
    case 331:
      return ok(GGroup::kMotion, "rigid tapping");
    case 382:
    case 383:
    case 384:
    case 385:
      return ok(GGroup::kMotion, "straight probe");
    case 400:
      return ok(GGroup::kCutterComp, "cutter compensation off");
    case 410:
      return ok(GGroup::kCutterComp, "cutter compensation left");
    case 411:
      return ok(GGroup::kCutterComp, "cutter compensation left, diameter from D");
    case 420:
      return ok(GGroup::kCutterComp, "cutter compensation right");
    case 421:
      return ok(GGroup::kCutterComp, "cutter compensation right, diameter from D");
    case 430:
      return ok(GGroup::kToolLength, "tool length offset");
    case 431:
      return ok(GGroup::kToolLength, "dynamic tool length offset");
    case 432:
      return ok(GGroup::kToolLength, "added tool length offset");
    case 490:
      return ok(GGroup::kToolLength, "tool length offset off");
    case 520:
      return ok(GGroup::kNonModal, "local coordinate offset");
    case 530:
      return ok(GGroup::kNonModal, "move in machine coordinates");
    case 540:
    case 550:
    case 560:
    case 570:
    case 580:
    case 590:
    case 591:
    case 592:
    case 593:
      return ok(GGroup::kCoordSystem, "work coordinate system");
    case 610:
      return ok(GGroup::kPathControl, "exact path mode");
    case 611:
      return ok(GGroup::kPathControl, "exact stop mode");
    case 640:
      return ok(GGroup::kPathControl, "blending mode");
    case 700:
      return ok(GGroup::kMotion, "lathe finishing cycle");
    case 710:
    case 711:
    case 712:
      return ok(GGroup::kMotion, "lathe roughing cycle");
    case 720:
    case 721:
    case 722:
      return ok(GGroup::kMotion, "lathe facing cycle");
    case 730:
    case 740:
    case 810:
    case 820:
    case 830:
    case 840:
    case 850:
    case 860:
    case 870:
    case 880:
    case 890:
      return ok(GGroup::kMotion, "canned cycle");
    case 760:
      return ok(GGroup::kMotion, "threading cycle");
    case 800:
      return ok(GGroup::kMotion, "cancel motion mode");
    case 900:
      return ok(GGroup::kDistance, "absolute distance mode");
    case 910:
      return ok(GGroup::kDistance, "incremental distance mode");
    case 901:
      return ok(GGroup::kArcDistance, "absolute arc centre mode");
    case 911:
      return ok(GGroup::kArcDistance, "incremental arc centre mode");
    case 920:
      return ok(GGroup::kNonModal, "G92 coordinate offset");
    case 921:
      return ok(GGroup::kNonModal, "reset the G92 offset");
    case 922:
      return ok(GGroup::kNonModal, "suspend the G92 offset");
    case 923:
      return ok(GGroup::kNonModal, "restore the G92 offset");
    case 930:
      return ok(GGroup::kFeedMode, "inverse time feed");
    case 940:
      return ok(GGroup::kFeedMode, "units per minute feed");
    case 950:
      return ok(GGroup::kFeedMode, "feed per revolution");
    case 960:
      return ok(GGroup::kSpindleMode, "constant surface speed");
    case 970:
      return ok(GGroup::kSpindleMode, "spindle RPM mode");
    case 980:
    case 990:
      return ok(GGroup::kCannedReturn, "canned cycle return mode");
    default:
      return {};
  }
}

CodeInfo m_code_info(int code10) {
  switch (code10) {
    case 0:
      return okm(MGroup::kStopping, "program stop");
    case 10:
      return okm(MGroup::kStopping, "optional stop");
    case 20:
      return okm(MGroup::kStopping, "program end");
    case 300:
      return okm(MGroup::kStopping, "program end and rewind");
    case 600:
      return {true, false, static_cast<int>(MGroup::kStopping), "pallet change"};
    case 990:
      return okm(MGroup::kStopping, "return from subprogram");
    case 30:
    case 40:
      return okm(MGroup::kSpindle, "spindle on");
    case 50:
      return okm(MGroup::kSpindle, "spindle stop");
    case 190:
      return okm(MGroup::kSpindle, "spindle orient");
    case 60:
      return okm(MGroup::kToolChange, "tool change");
    case 610:
      return okm(MGroup::kToolChange, "set tool number");
    case 70:
    case 80:
      return okm(MGroup::kCoolant, "coolant on");
    case 90:
      return okm(MGroup::kCoolant, "coolant off");
    case 980:
      return okm(MGroup::kSubprogram, "subprogram call");
    case 520:
      // LinuxCNC's adaptive feed control: M52 P1 (or no P) on, M52 P0 off (spec 04).
      return okm(MGroup::kSubprogram, "adaptive feed control");
    case 480:
    case 490:
    case 500:
    case 510:
    case 530:
      return {true, false, static_cast<int>(MGroup::kSubprogram), "override control"};
    case 620:
    case 630:
    case 640:
    case 650:
    case 660:
    case 670:
    case 680:
      return {true, false, static_cast<int>(MGroup::kSubprogram), "digital/analog I/O"};
    case 700:
    case 710:
    case 720:
    case 730:
      return {true, false, static_cast<int>(MGroup::kSubprogram), "modal state save/restore"};
    case 1600:
      return okm(MGroup::kUser, "direction feed correction on");
    case 1610:
      return okm(MGroup::kUser, "direction feed correction off");
    default:
      if (code10 >= 1000 && code10 <= 1990 && code10 % 10 == 0) {
        return {true, false, static_cast<int>(MGroup::kSubprogram), "user-defined M code"};
      }
      return {};
  }
}

std::string code_text(char letter, int code10) {
  std::string s(1, letter);
  s += std::to_string(code10 / 10);
  if (code10 % 10 != 0) {
    s += '.';
    s += std::to_string(code10 % 10);
  }
  return s;
}

}  // namespace cncore::interp
