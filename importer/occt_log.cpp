// OCCT's console output goes to our log (stderr), never to stdout: stdout of
// the CLI carries results (JSON, converted files piped on), and the readers
// otherwise print coloured chatter there through Message::DefaultMessenger().
#include <cstdio>
#include <cstdlib>
#include <mutex>

#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Message_PrinterOStream.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_AsciiString.hxx>

#include "importer/internal.h"

namespace nurbsrt::occt {
namespace {

class StderrPrinter : public Message_Printer {
public:
    explicit StderrPrinter(Message_Gravity threshold) { SetTraceLevel(threshold); }

protected:
    void send(const TCollection_AsciiString& text, const Message_Gravity gravity) const override {
        if (gravity < myTraceLevel) return;
        // One fprintf per message keeps lines from concurrent threads whole.
        std::fprintf(stderr, "[occt] %s\n", text.ToCString());
    }
};

}  // namespace

void route_occt_messages() {
    static std::once_flag once;
    std::call_once(once, [] {
        const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
        messenger->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
        // NURBSRT_OCCT_VERBOSE=1 shows OCCT's info/trace messages too (debugging imports).
        const char* verbose = std::getenv("NURBSRT_OCCT_VERBOSE");
        const Message_Gravity threshold = (verbose != nullptr && verbose[0] == '1') ? Message_Trace : Message_Fail;
        messenger->AddPrinter(new StderrPrinter(threshold));
    });
}

std::string failure_text(const Standard_Failure& f) {
    std::string text = f.DynamicType()->Name();
    const char* msg = f.GetMessageString();
    if (msg != nullptr && msg[0] != '\0') {
        text += ": ";
        text += msg;
    }
    return text;
}

}  // namespace nurbsrt::occt
