// A source that does not follow .clang-format: the test format_catches_drift expects
// tools/check_format.sh to reject it (a format check that cannot fail checks nothing).
int  twice( int x ){return 2*x;}
