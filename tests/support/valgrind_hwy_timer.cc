// Preloaded into processes run under valgrind (tests/detector's memcheck test): libhwy, which OpenCV's
// image codecs load, measures its timer's resolution with rdtscp when it is loaded, and valgrind does not
// emulate rdtscp. This definition takes the place of libhwy's: the timer is never used by mcmt.
namespace hwy {
namespace platform {
unsigned long TimerResolution() { return 1; }  // NOLINT(runtime/int): libhwy's own signature
}  // namespace platform
}  // namespace hwy
