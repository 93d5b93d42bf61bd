"""The accuracy study: metrics, the study itself, its report and its work-precision figures."""
