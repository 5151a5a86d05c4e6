// frame_rx: parses request frames from the UART byte stream (docs/REGISTER_MAP.md, "UART frames").
//
// A frame is SYNC, LEN, TYPE, body, CRC-16 (high byte first) over LEN, TYPE and body. The parser
// hunts for SYNC, collects LEN bytes (at most MAX_LEN), checks the CRC, and then the type and length:
//   - CRC wrong                           -> error BAD_CRC, detail = TYPE byte
//   - LEN 0 or above MAX_LEN              -> error MALFORMED, detail = LEN (the frame is not buffered)
//   - CRC right, unknown TYPE or wrong LEN -> error MALFORMED, detail = TYPE byte
//   - a gap longer than TIMEOUT_CYCLES inside a frame (truncated) -> error MALFORMED, detail = 0xFF
// Only a frame that passes every check becomes a request, so a bad frame can never write a register.
// Assumptions: one event is outstanding at a time; while it is not taken (ev_ready_i low) no byte
// is accepted (the UART receiver counts an overrun if the host does not wait for its answer).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module frame_rx #(
    // The inter-byte gap that ends a frame (FRAME_GAP_TIMEOUT_US, 1 ms) at the board clock: 12000 cycles.
    parameter integer TIMEOUT_CYCLES = `OMNILOC_BOARD_CLOCK_HZ / 1000 * `OMNILOC_FRAME_GAP_TIMEOUT_US / 1000
) (
    input  wire                       clk_i,
    input  wire                       rst_i,
    // bytes from the UART receiver
    input  wire [7:0]                 byte_i,
    input  wire                       byte_valid_i,
    output wire                       byte_ready_o,
    // one event: a request (ev_error_o = 0, ev_code_o = frame TYPE) or an error to report
    // (ev_error_o = 1, ev_code_o = error code, ev_addr_o = detail)
    output reg                        ev_valid_o,
    input  wire                       ev_ready_i,
    output reg                        ev_error_o,
    output reg  [7:0]                 ev_code_o,
    // the request's kind, decoded with TYPE (0 with an error; a SNAPSHOT_REQ is neither), so that
    // link_engine's bus strobes are one LUT level from flip-flops (the board's limiting path)
    output reg                        ev_read_o,
    output reg                        ev_write_o,
    output reg  [`OMNILOC_ADDR_W-1:0] ev_addr_o,
    output reg  [`OMNILOC_DATA_W-1:0] ev_data_o
);

localparam integer ADDR_W = `OMNILOC_ADDR_W;
localparam integer DATA_W = `OMNILOC_DATA_W;
// The longest request is WRITE_REQ; its body fills body_q exactly.
localparam integer MAX_BODY = `OMNILOC_FRAME_WRITE_REQ_BODY_BYTES;
localparam integer MAX_LEN = 1 + MAX_BODY;
// body_q is shifted in from the top, so a READ_REQ body (REG_ADDR layout) ends up in its top bytes.
localparam integer READ_BASE = 8 * (MAX_BODY - `OMNILOC_FRAME_READ_REQ_BODY_BYTES);
localparam integer TIMER_W = $clog2(TIMEOUT_CYCLES + 1);
localparam integer TIMEOUT_I = TIMEOUT_CYCLES;
localparam [TIMER_W-1:0] TIMEOUT = TIMEOUT_I[TIMER_W-1:0];

localparam [2:0] S_HUNT = 3'd0, S_LEN = 3'd1, S_TYPE = 3'd2, S_BODY = 3'd3,
                 S_CRC_HI = 3'd4, S_CRC_LO = 3'd5, S_EVENT = 3'd6;

reg [2:0]         state_q;
reg [7:0]         len_q;
reg [7:0]         left_q;      // body bytes still to come
reg [7:0]         type_q;
reg [8*MAX_BODY-1:0] body_q;   // body bytes as they came, shifted in from the top
reg [15:0]        crc_q;
reg [7:0]         crc_hi_q;
reg [TIMER_W-1:0] timer_q;

// Input stage: a byte is taken into in_byte_q (load) and its checks against the byte itself are
// registered with it (in_*_q); the parser works on it in the next cycle (take), so no decision
// of the parser depends on byte_i in the same cycle. One byte a cycle at most every other
// cycle, far above the UART's rate (120 cycles a byte at 12 MHz / 1 Mbaud).
reg       in_full_q;
reg [7:0] in_byte_q;
reg       in_sync_q;      // the byte is SYNC
reg       in_len_bad_q;   // as LEN: 0 or above MAX_LEN
reg       in_crc_ok_q;    // as CRC_LO: {crc_hi_q, byte} == crc_q
assign byte_ready_o = (state_q != S_EVENT) && !in_full_q;
wire load = byte_valid_i && byte_ready_o;
wire take = in_full_q;

wire [15:0] crc_next;
crc16_ccitt crc_step (.crc_i(crc_q), .data_i(in_byte_q), .crc_o(crc_next));

// Is (TYPE, LEN) a request this board serves? Decided when TYPE is parsed (len_q is known then).
wire [7:0] body_len = len_q - 8'd1;
reg known_q, known_write_q, known_read_q;
wire known_read_d  = (in_byte_q == `OMNILOC_FRAME_READ_REQ)     && (body_len == `OMNILOC_FRAME_READ_REQ_BODY_BYTES);
wire known_write_d = (in_byte_q == `OMNILOC_FRAME_WRITE_REQ)    && (body_len == `OMNILOC_FRAME_WRITE_REQ_BODY_BYTES);
wire known_snap_d  = (in_byte_q == `OMNILOC_FRAME_SNAPSHOT_REQ) && (body_len == `OMNILOC_FRAME_SNAPSHOT_REQ_BODY_BYTES);
wire in_frame = (state_q != S_HUNT) && (state_q != S_EVENT);

// Input stage and data registers: no reset (each is written before it is used).
always @(posedge clk_i) begin
    if (load) begin
        in_byte_q    <= byte_i;
        in_sync_q    <= (byte_i == `OMNILOC_FRAME_SYNC);
        in_len_bad_q <= (byte_i == 8'd0) || (byte_i > MAX_LEN[7:0]);
        in_crc_ok_q  <= ({crc_hi_q, byte_i} == crc_q);
    end
    if (take && state_q == S_TYPE) begin
        known_q       <= known_read_d || known_write_d || known_snap_d;
        known_write_q <= known_write_d;
        known_read_q  <= known_read_d;
    end
end

task raise_error(input [7:0] code, input [7:0] detail);
    begin
        ev_error_o <= 1'b1;
        ev_code_o  <= code;
        ev_read_o  <= 1'b0;
        ev_write_o <= 1'b0;
        ev_addr_o  <= detail;
        ev_data_o  <= {DATA_W{1'b0}};
        ev_valid_o <= 1'b1;
        state_q    <= S_EVENT;
    end
endtask

always @(posedge clk_i) begin
    if (rst_i) begin
        state_q    <= S_HUNT;
        in_full_q  <= 1'b0;
        len_q      <= 8'd0;
        left_q     <= 8'd0;
        type_q     <= 8'd0;
        body_q     <= {8*MAX_BODY{1'b0}};
        crc_q      <= `OMNILOC_CRC_INIT;
        crc_hi_q   <= 8'd0;
        timer_q    <= {TIMER_W{1'b0}};
        ev_valid_o <= 1'b0;
        ev_error_o <= 1'b0;
        ev_code_o  <= 8'd0;
        ev_read_o  <= 1'b0;
        ev_write_o <= 1'b0;
        ev_addr_o  <= {ADDR_W{1'b0}};
        ev_data_o  <= {DATA_W{1'b0}};
    end else begin
        in_full_q <= load;
        // Inter-byte timeout inside a frame, from the cycle a byte is taken by the input stage
        // (a SYNC parsed now opens the frame, as if it had been parsed when it was taken).
        if (load) timer_q <= {TIMER_W{1'b0}};
        else if (in_frame || (take && state_q == S_HUNT && in_sync_q)) begin
            if (timer_q != TIMEOUT) timer_q <= timer_q + 1'b1;
        end else begin
            timer_q <= {TIMER_W{1'b0}};
        end

        if (in_frame && !take && !load && timer_q == TIMEOUT) begin
            raise_error(`OMNILOC_ERR_MALFORMED, 8'hFF);
        end else begin
            case (state_q)
                S_HUNT: if (take && in_sync_q) begin
                    state_q <= S_LEN;
                    crc_q   <= `OMNILOC_CRC_INIT;
                end
                S_LEN: if (take) begin
                    if (in_len_bad_q) begin
                        raise_error(`OMNILOC_ERR_MALFORMED, in_byte_q);
                    end else begin
                        len_q   <= in_byte_q;
                        left_q  <= in_byte_q - 8'd1;
                        crc_q   <= crc_next;
                        state_q <= S_TYPE;
                    end
                end
                S_TYPE: if (take) begin
                    type_q  <= in_byte_q;
                    crc_q   <= crc_next;
                    body_q  <= {8*MAX_BODY{1'b0}};
                    state_q <= (left_q == 8'd0) ? S_CRC_HI : S_BODY;
                end
                S_BODY: if (take) begin
                    body_q  <= {in_byte_q, body_q[8*MAX_BODY-1:8]};
                    crc_q   <= crc_next;
                    left_q  <= left_q - 8'd1;
                    if (left_q == 8'd1) state_q <= S_CRC_HI;
                end
                S_CRC_HI: if (take) begin
                    crc_hi_q <= in_byte_q;
                    state_q  <= S_CRC_LO;
                end
                S_CRC_LO: if (take) begin
                    if (!in_crc_ok_q) begin
                        raise_error(`OMNILOC_ERR_BAD_CRC, type_q);
                    end else if (!known_q) begin
                        raise_error(`OMNILOC_ERR_MALFORMED, type_q);
                    end else begin
                        // The fields at their layout's offsets (a WRITE_REQ fills body_q, a
                        // READ_REQ sits in its top bytes).
                        ev_error_o <= 1'b0;
                        ev_code_o  <= type_q;
                        ev_read_o  <= known_read_q;
                        ev_write_o <= known_write_q;
                        ev_addr_o  <= known_write_q ? body_q[`OMNILOC_BODY_REG_VALUE_ADDR_LSB +: `OMNILOC_BODY_REG_VALUE_ADDR_W]
                                                  : body_q[READ_BASE + `OMNILOC_BODY_REG_ADDR_ADDR_LSB +: `OMNILOC_BODY_REG_ADDR_ADDR_W];
                        ev_data_o  <= known_write_q ? body_q[`OMNILOC_BODY_REG_VALUE_DATA_LSB +: `OMNILOC_BODY_REG_VALUE_DATA_W]
                                                  : {DATA_W{1'b0}};
                        ev_valid_o <= 1'b1;
                        state_q    <= S_EVENT;
                    end
                end
                default: if (ev_ready_i) begin   // S_EVENT
                    ev_valid_o <= 1'b0;
                    state_q    <= S_HUNT;
                end
            endcase
        end
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
always @(*) if (!f_past_valid) assume(rst_i);   // start from reset
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i)) begin
        // An event is held stable until taken.
        if ($past(ev_valid_o) && !$past(ev_ready_i))
            assert(ev_valid_o && ev_error_o == $past(ev_error_o) && ev_code_o == $past(ev_code_o)
                   && ev_addr_o == $past(ev_addr_o) && ev_data_o == $past(ev_data_o));
        // Only a request type this board serves leaves as a request.
        if (ev_valid_o && !ev_error_o)
            assert(ev_code_o == `OMNILOC_FRAME_READ_REQ || ev_code_o == `OMNILOC_FRAME_WRITE_REQ
                   || ev_code_o == `OMNILOC_FRAME_SNAPSHOT_REQ);
        // The decoded kind is the TYPE's, and none with an error.
        if (ev_valid_o) begin
            assert(ev_read_o == (!ev_error_o && ev_code_o == `OMNILOC_FRAME_READ_REQ));
            assert(ev_write_o == (!ev_error_o && ev_code_o == `OMNILOC_FRAME_WRITE_REQ));
        end
        // A new request event follows the last CRC byte of a frame (the CRC itself is
        // checked against a golden model in tests/link/tb_frame_rx.cpp).
        if (ev_valid_o && !$past(ev_valid_o) && !ev_error_o) assert($past(state_q) == S_CRC_LO);
        assert(ev_valid_o == (state_q == S_EVENT));
        assert(left_q < MAX_LEN);
        // The input stage's flags describe its byte (auxiliary invariant for the induction).
        // known_q was decided from TYPE (auxiliary invariant for the induction).
        if ((state_q == S_BODY || state_q == S_CRC_HI || state_q == S_CRC_LO) && known_q)
            assert(type_q == `OMNILOC_FRAME_READ_REQ || type_q == `OMNILOC_FRAME_WRITE_REQ
                   || type_q == `OMNILOC_FRAME_SNAPSHOT_REQ);
        if (state_q == S_BODY || state_q == S_CRC_HI || state_q == S_CRC_LO) begin
            assert(known_read_q == (known_q && type_q == `OMNILOC_FRAME_READ_REQ));
            assert(known_write_q == (known_q && type_q == `OMNILOC_FRAME_WRITE_REQ));
        end
        if (in_full_q) begin
            assert(in_len_bad_q == ((in_byte_q == 8'd0) || (in_byte_q > MAX_LEN[7:0])));
            assert(in_sync_q == (in_byte_q == `OMNILOC_FRAME_SYNC));
        end
    end
end

// Each property reachable: a request served, an error event raised.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (ev_valid_o && !ev_error_o && ev_code_o == `OMNILOC_FRAME_SNAPSHOT_REQ);
        cover (ev_valid_o && ev_error_o && ev_code_o == `OMNILOC_ERR_MALFORMED);
    end
end
`endif

endmodule

`default_nettype wire
