/* gi_version: the version of the programs and of the protocol they speak. */
#ifndef GI_VERSION_H
#define GI_VERSION_H

#define GI_VERSION "0.1.0"

#endif
