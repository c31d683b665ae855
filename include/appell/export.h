/* Appell: the one visibility macro through which the public API is exported. */
#ifndef APPELL_EXPORT_H
#define APPELL_EXPORT_H

#if defined(__GNUC__) || defined(__clang__)
#define AP_API __attribute__((visibility("default")))
#else
#define AP_API
#endif

#endif
